"""Base class of acceleration-level tasks: ``weight * ||J qdd + drift - a_des||^2``."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from wbc.errors import ConfigurationError
from wbc.validation import as_float, as_vector


class Task:
    """An acceleration-level task on the generalized accelerations ``qdd`` (nv,).

    Each tick, :meth:`update` reads Pinocchio data (already updated by the controller with
    ``computeAllTerms`` and frame placements) and fills:

    - ``error`` (dim,): target minus current value, in the task space;
    - ``error_rate`` (dim,): target velocity minus current velocity;
    - ``jacobian`` (dim, nv): the task velocity is ``jacobian @ v``;
    - ``drift`` (dim,): the task acceleration at ``qdd = 0`` (``Jdot v``);
    - ``desired_acceleration`` (dim,): ``kp * error + kd * error_rate + feedforward``.

    The QP term is ``weight * ||jacobian @ qdd + drift - desired_acceleration||^2``.
    Gains default to critical damping, ``kd = 2 sqrt(kp)``.
    """

    #: Number of task rows.
    dim: int = 0

    def __init__(self, *, kp: float, kd: float | None = None, weight: float = 1.0,
                 nv: int = 18):
        """Args:
            kp: Stiffness [1/s^2].
            kd: Damping [1/s]; ``None`` for critical damping ``2 sqrt(kp)``.
            weight: Cost weight (dimensionless, relative to other tasks).
            nv: Dimension of the velocity vector.
        """
        self.nv = nv
        self.set_gains(kp=kp, kd=kd)
        self.weight = as_float("weight", weight, low=0.0)
        self.error = np.zeros(self.dim)
        self.error_rate = np.zeros(self.dim)
        self.jacobian = np.zeros((self.dim, nv))
        self.drift = np.zeros(self.dim)
        self.desired_acceleration = np.zeros(self.dim)
        self.feedforward = np.zeros(self.dim)

    def set_gains(self, *, kp: float, kd: float | None = None) -> None:
        """Set stiffness ``kp`` [1/s^2] and damping ``kd`` [1/s] (critical when ``None``)."""
        kp = as_float("kp", kp, low=0.0)
        kd = 2.0 * math.sqrt(kp) if kd is None else as_float("kd", kd, low=0.0)
        self.kp, self.kd = kp, kd

    def set_weight(self, weight: float) -> None:
        """Set the cost weight (>= 0)."""
        self.weight = as_float("weight", weight, low=0.0)

    def set_feedforward(self, acceleration: np.ndarray) -> None:
        """Set the feed-forward task acceleration (dim,)."""
        self.feedforward = as_vector(f"{type(self).__name__}.feedforward", acceleration, self.dim)

    def update(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> None:
        """Recompute error, Jacobian, drift and desired acceleration.

        Args:
            model: The Pinocchio model.
            data: Its data, updated at ``(q, v)`` by ``computeAllTerms`` (zero-acceleration
                bias terms) and ``updateFramePlacements``.
            q: Configuration (nq,). v: Velocity (nv,).
        """
        self.compute(model, data, q, v)
        desired = self.desired_acceleration
        np.multiply(self.kp, self.error, out=desired)
        desired += self.kd * self.error_rate
        desired += self.feedforward

    def compute(self, model: pin.Model, data: pin.Data, q: np.ndarray, v: np.ndarray) -> None:
        """Fill ``error``, ``error_rate``, ``jacobian`` and ``drift``; subclasses implement."""
        raise NotImplementedError

    def _require_target(self, target: np.ndarray | None) -> np.ndarray:
        if target is None:
            raise ConfigurationError(
                f"{type(self).__name__}: target not set; call set_target(...) first"
            )
        return target
