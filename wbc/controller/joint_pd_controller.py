"""Joint PD with contact-consistent gravity compensation: the simplest controller that stands."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from wbc.core.validation import as_float, as_vector, check_name
from wbc.model.description import FOOT_FRAMES, LEGS, Go2Description


class JointPdController:
    """``tau = kp (q_ref - q) - kd v + tau_gravity``, with gravity carried by the stance feet.

    The body's weight is split over the stance feet by the minimum-norm set of foot forces
    that balances gravity on the floating base; ``tau_gravity`` holds the robot at rest with
    those forces, so the PD only corrects deviations. Not a balance controller: it is the
    baseline the whole-body controller is compared with, and a safe fallback.
    """

    def __init__(
        self,
        q_ref: Sequence[float] | np.ndarray,
        *,
        kp: float = 60.0,
        kd: float = 3.0,
        stance_legs: Sequence[str] = LEGS,
        description: Go2Description | None = None,
    ):
        """Args:
            q_ref: Reference configuration (nq,) in Pinocchio convention.
            kp: Joint stiffness [N m / rad].
            kd: Joint damping [N m s / rad].
            stance_legs: Legs assumed on the ground for gravity compensation.
            description: The robot files (found automatically by default).
        """
        self.description = description or Go2Description.default()
        self.model = self.description.model
        self.data = self.model.createData()
        self.q_ref = as_vector("q_ref", q_ref, self.model.nq)
        self.kp = as_float("kp", kp, low=0.0)
        self.kd = as_float("kd", kd, low=0.0)
        for leg in stance_legs:
            check_name("leg", leg, LEGS)
        self._frames = [self.model.getFrameId(FOOT_FRAMES[leg]) for leg in stance_legs]

    def gravity_torques(self, q: np.ndarray) -> np.ndarray:
        """Joint torques [N m] (nv - 6,) that hold ``q`` at rest on the stance feet."""
        g = pin.computeGeneralizedGravity(self.model, self.data, q)
        if not self._frames:
            return g[6:].copy()
        pin.computeJointJacobians(self.model, self.data, q)
        pin.updateFramePlacements(self.model, self.data)
        jac = np.vstack([
            pin.getFrameJacobian(self.model, self.data, f, pin.LOCAL_WORLD_ALIGNED)[:3]
            for f in self._frames
        ])
        forces = np.linalg.lstsq(jac[:, :6].T, g[:6], rcond=None)[0]
        return g[6:] - jac[:, 6:].T @ forces

    def compute(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Joint torques [N m] (nv - 6,), description order, for state ``(q, v)``."""
        q = as_vector("q", q, self.model.nq)
        v = as_vector("v", v, self.model.nv)
        return (self.kp * (self.q_ref[7:] - q[7:]) - self.kd * v[6:]
                + self.gravity_torques(q))

