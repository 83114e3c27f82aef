"""Stance-contact condition: feet on the ground do not accelerate."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import pinocchio as pin

from tasks import task_kernels
from tasks.task import Task
from wbc.core.errors import ConfigurationError

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class ContactTask(Task):
    """``J qdd + drift = -kd * contact velocity`` for one or more rolling point contacts.

    Each foot is a sphere of radius ``radius_m`` centred on its frame, touching flat ground
    at the point ``d = (0, 0, -radius_m)`` (world) below its centre. Rolling without
    slipping keeps that point still: ``v_c + omega x d = 0``, so the rows are
    ``J = J_lin - [d]x J_ang`` and, ``d`` being constant in the world while the sphere
    rolls, ``drift = a_lin - [d]x alpha`` (classical accelerations at ``qdd = 0``). The
    same ``J`` maps the contact forces, applied at the contact point, to joint torques.
    With ``radius_m = 0`` this is the plain point contact at the frame origin.

    The rows of foot ``i`` are ``3 i .. 3 i + 2`` (world x, y, z). The controller uses them
    in equality constraints, not as a cost; computing all feet in one task shares the work
    with the contact forces' Jacobians. ``kp`` is zero (a stance foot has no position
    target); ``kd`` damps any residual sliding. ``error_rate`` is minus the contact points'
    velocities [m/s].
    """

    def __init__(self, model: pin.Model, frames: Sequence[str], *, kd: float = 0.0,
                 radius_m: float = 0.0):
        """Args:
            model: The Pinocchio model holding the frames.
            frames: Foot frame names, e.g. ``["FL_foot", "FR_foot", "RL_foot", "RR_foot"]``.
            kd: Damping of the contact points' velocity [1/s].
            radius_m: Radius of the foot spheres [m].
        """
        frames = list(frames)
        for frame in frames:
            if not model.existFrame(frame):
                names = [f.name for f in model.frames]
                raise ConfigurationError(f"frames: unknown frame {frame!r}; valid frames: {names}")
        self.frames = tuple(frames)
        self.frame_ids = [model.getFrameId(f) for f in frames]
        self.dim = 3 * len(frames)
        self.radius_m = float(radius_m)
        super().__init__(kp=0.0, kd=kd, weight=1.0, nv=model.nv)
        self._has_target = True  # the target is implicit: no acceleration

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        k = kinematics
        return task_kernels.rolling_contacts, (
            k.frame_jacobian, k.frame_drift, self.frame_indices, self.radius_m, self.gains,
            k.v, self.jacobian, self.drift, self.error_rate, self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
