"""What one control tick returns: torques, accelerations, forces, errors, status, timings."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np


class ControlStatus(enum.Enum):
    """Outcome of one control tick."""

    #: The QP was solved; ``tau`` is the whole-body command.
    OK = "ok"
    #: The backend failed on a feasible QP; ``tau`` is a fresh DAQP solution of it.
    RESOLVED = "resolved"
    #: The QP was infeasible; ``tau`` solves it with the named limit group relaxed (and is
    #: clipped to the torque limits): the safest command while the robot is pushed hard.
    RELAXED = "relaxed"
    #: No usable solution (solver error, bad state, infeasible physics); ``tau`` is the safe
    #: fallback, the last good torques with joint damping.
    FALLBACK = "fallback"


@dataclass
class ControlOutput:
    """The result of :meth:`wbc.WholeBodyController.step`. Never ``None``."""

    #: Joint torques [N m] (12,), description order.
    tau: np.ndarray
    #: Generalized accelerations (18,) [m/s^2, rad/s^2]; NaN on fallback.
    qdd: np.ndarray
    #: Contact forces [N] (4, 3), world frame, one row per leg (FL, FR, RL, RR).
    forces: np.ndarray
    status: ControlStatus
    #: Why the tick fell back (empty when OK).
    message: str = ""
    #: The constraint group that made the QP infeasible, when it could be named.
    infeasible_group: str = ""
    #: Per-task error norms: ``{"com": m, "base_orientation": rad, "FR_foot": m, ...}``.
    task_errors: dict[str, float] = field(default_factory=dict)
    #: Stage durations [s]: ``model``, ``tasks``, ``assembly``, ``solve``, ``total``.
    timings: dict[str, float] = field(default_factory=dict)
    #: Largest equality and inequality violation of the returned QP solution.
    violation: tuple[float, float] = (0.0, 0.0)

    @property
    def ok(self) -> bool:
        """True when the QP was solved."""
        return self.status is ControlStatus.OK
