"""Centre-of-mass position task."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import task_kernels
from tasks.task import Task

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics

_XYZ = np.arange(3)


class ComTask(Task):
    """Track a world-frame centre-of-mass position [m] (and velocity [m/s]).

    Reads the kinematics' ``com_position``, ``com_velocity``, ``com_jacobian`` and
    ``com_drift`` (the CoM acceleration at zero ``qdd``).
    """

    dim = 3

    def __init__(self, *, kp: float = 100.0, kd: float | None = None, weight: float = 10.0):
        super().__init__(kp=kp, kd=kd, weight=weight)

    def set_target(self, position: np.ndarray, velocity: np.ndarray | None = None) -> None:
        """Set the target position [m] and velocity [m/s] (world frame); copies them."""
        self._set_reference("ComTask", position, velocity)

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        self._require_target()
        k = kinematics
        return task_kernels.com_task, (
            k.com_jacobian, k.com_position, k.com_velocity, k.com_drift, _XYZ, self.reference,
            self.gains, self.jacobian, self.drift, self.error, self.error_rate,
            self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
