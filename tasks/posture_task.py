"""Joint posture task: pull the actuated joints towards a reference configuration."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from tasks.task import Task
from wbc.validation import as_vector


class PostureTask(Task):
    """Track joint positions [rad] of the ``n_joints`` actuated joints (after the free flyer)."""

    def __init__(self, *, n_joints: int = 12, kp: float = 25.0, kd: float | None = None,
                 weight: float = 0.05):
        self.dim = n_joints
        super().__init__(kp=kp, kd=kd, weight=weight, nv=6 + n_joints)
        self.jacobian[:, 6:] = np.eye(n_joints)
        self.target: np.ndarray | None = None

    def set_target(self, joint_positions: np.ndarray) -> None:
        """Set the target joint positions [rad] (n_joints,), description order; copies them."""
        self.target = as_vector("PostureTask.target", joint_positions, self.dim)

    def compute(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> None:
        target = self._require_target(self.target)
        np.subtract(target, q[7:], out=self.error)
        np.negative(v[6:], out=self.error_rate)
