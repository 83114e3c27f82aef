"""Joint posture task: pull the actuated joints towards a reference configuration."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import task_kernels
from tasks.task import Task
from tasks.task_block import TaskBlock

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class PostureTask(Task):
    """Track joint positions [rad] of the ``n_joints`` actuated joints (after the free flyer).

    Besides the scalar ``weight``, each joint has a relative weight in ``joint_weights``
    (the task's ``row_weights``, ones by default): a joint trajectory raises a few joints'
    weights to track them tightly.
    """

    def __init__(self, *, n_joints: int = 12, kp: float = 25.0, kd: float | None = None,
                 weight: float = 0.05):
        self.dim = n_joints
        super().__init__(kp=kp, kd=kd, weight=weight, nv=6 + n_joints)

    def setup(self, block: TaskBlock) -> None:
        block.jacobian[:, 6:] = np.eye(self.dim)  # the joints' accelerations, after the base's

    @property
    def joint_weights(self) -> np.ndarray:
        """The per-joint multipliers of ``weight`` (n_joints,), the task's ``row_weights``."""
        return self.row_weights

    def set_target(self, joint_positions: np.ndarray, velocity: np.ndarray | None = None) -> None:
        """Set the target joint positions [rad] and velocities [rad/s]; copies them."""
        self._set_reference("PostureTask", joint_positions, velocity)

    def set_joint_weights(self, weights: np.ndarray) -> None:
        """Relative weights (n_joints,), each >= 0, multiplying ``weight`` joint by joint."""
        self._check_and_store_row_weights("PostureTask.joint_weights", weights)

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        self._require_target()
        return task_kernels.posture_task, (
            kinematics.q, kinematics.v, self.reference, self.gains, self.error,
            self.error_rate, self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
