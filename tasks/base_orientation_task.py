"""Floating-base orientation task."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from tasks import task_kernels
from tasks.task import Task
from tasks.task_block import InPlace, TaskBlock
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class BaseOrientationTask(Task):
    """Track a world-frame orientation of the floating base.

    Errors and rates are in the base frame, where the free-flyer velocity's angular part
    is ``v[3:6]``: the Jacobian is a selection and the drift is zero. ``reference`` rows 1
    and 2 hold a target angular velocity and a feed-forward (base frame).
    """

    dim = 3
    #: Target rotation ``R_world_base`` (updated in place: the compiled kernel reads it).
    rotation = InPlace()
    #: Added to the desired angular acceleration [rad/s^2] (a controller's integral term;
    #: written in place).
    bias = InPlace()

    def __init__(self, *, kp: float = 100.0, kd: float | None = None, weight: float = 5.0,
                 nv: int | None = None):
        self.__dict__["_rotation"] = np.eye(3)
        self.__dict__["_bias"] = np.zeros(3)
        super().__init__(kp=kp, kd=kd, weight=weight, nv=nv)
        self._has_target = True

    def setup(self, block: TaskBlock) -> None:
        block.jacobian[:, 3:6] = np.eye(3)  # the base's angular velocity, v[3:6]

    def set_target(self, rotation: np.ndarray) -> None:
        """Set the target rotation ``R_world_base`` (3x3, orthonormal); copies it."""
        rotation = np.asarray(rotation, dtype=float)
        flat = as_vector("BaseOrientationTask.target", rotation.reshape(-1), 9).reshape(3, 3)
        if not np.allclose(flat @ flat.T, np.eye(3), atol=1e-6) or np.linalg.det(flat) < 0:
            raise ConfigurationError(
                "BaseOrientationTask.target: expected a rotation matrix (orthonormal, det +1)"
            )
        self.rotation[:] = flat

    @property
    def target(self) -> np.ndarray:
        """A copy of the target rotation (3x3)."""
        return self.rotation.copy()

    def set_rpy(self, roll: float, pitch: float, yaw: float) -> None:
        """Set the target from roll, pitch, yaw [rad] (extrinsic X, Y, Z)."""
        self.set_target(pin.rpy.rpyToMatrix(float(roll), float(pitch), float(yaw)))

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        return task_kernels.base_orientation_task, (
            kinematics.base_rotation, kinematics.v, self.rotation, self.reference, self.bias,
            self.gains, self.error, self.error_rate, self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
