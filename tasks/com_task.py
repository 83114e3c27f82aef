"""Centre-of-mass position task."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from tasks.task import Task


class ComTask(Task):
    """Track a world-frame centre-of-mass position [m] (and velocity [m/s]).

    Reads ``data.com``, ``data.vcom``, ``data.Jcom`` (from ``computeAllTerms``) and the
    zero-acceleration ``data.acom`` (from ``centerOfMass(..., ACCELERATION)``).
    """

    dim = 3

    def __init__(self, *, kp: float = 100.0, kd: float | None = None, weight: float = 10.0):
        super().__init__(kp=kp, kd=kd, weight=weight)

    def set_target(self, position: np.ndarray, velocity: np.ndarray | None = None) -> None:
        """Set the target position [m] and velocity [m/s] (world frame); copies them."""
        self._set_reference("ComTask", position, velocity)

    def compute(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> None:
        np.subtract(self._require_target(), data.com[0], out=self.error)
        np.subtract(self.reference[1], data.vcom[0], out=self.error_rate)
        self.jacobian[:] = data.Jcom
        self.drift[:] = data.acom[0]
