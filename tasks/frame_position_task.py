"""Position task on a frame (a foot, the base), on all axes or a subset."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from tasks import task_kernels
from tasks.task import Task
from wbc.core.errors import ConfigurationError

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics

_AXES = {"x": 0, "y": 1, "z": 2}


class FramePositionTask(Task):
    """Track the world position [m] of a frame's origin on the chosen axes.

    Uses the ``LOCAL_WORLD_ALIGNED`` Jacobian and the classical (not spatial) acceleration
    as drift, so ``J qdd + drift`` is the second derivative of the world position.
    """

    def __init__(self, model: pin.Model, frame: str, *, axes: str = "xyz", kp: float = 400.0,
                 kd: float | None = None, weight: float = 10.0):
        """Args:
            model: The Pinocchio model holding ``frame``.
            frame: Frame name, e.g. ``"FR_foot"``.
            axes: World axes to track, a subset of ``"xyz"`` (``"z"`` for a height task).
            kp: Stiffness [1/s^2]; kd: damping [1/s] (critical when ``None``).
            weight: Cost weight.
        """
        if not model.existFrame(frame):
            names = [f.name for f in model.frames]
            raise ConfigurationError(f"frame: unknown frame {frame!r}; valid frames: {names}")
        if not axes or any(a not in _AXES for a in axes) or len(set(axes)) != len(axes):
            raise ConfigurationError(f"axes: expected a subset of 'xyz', received {axes!r}")
        self.frame = frame
        self.frames = (frame,)
        self.frame_id = model.getFrameId(frame)
        self.axes = axes
        self._axes = np.array([_AXES[a] for a in axes], dtype=np.int64)
        self.dim = len(axes)
        super().__init__(kp=kp, kd=kd, weight=weight, nv=model.nv)

    def set_target(self, position: np.ndarray, velocity: np.ndarray | None = None) -> None:
        """Set the target position [m] and velocity [m/s] on the task's axes; copies them."""
        self._set_reference(self.frame, position, velocity)

    def _field(self) -> str:
        return self.frame

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        self._require_target()
        k = kinematics
        return task_kernels.frame_position_task, (
            k.frame_jacobian, k.frame_position, k.frame_velocity, k.frame_drift,
            int(self.frame_indices[0]), self._axes, self.reference, self.gains, self.jacobian,
            self.drift, self.error, self.error_rate, self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
