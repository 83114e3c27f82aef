"""What one control tick returns: the motor command, torques, accelerations, forces, status."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

import numpy as np

from wbc.robot_io.motor_command import MotorCommand


class ControlStatus(enum.Enum):
    """Outcome of one control tick."""

    #: The QP was solved; ``tau`` is the whole-body command.
    OK = "ok"
    #: The backend failed on a feasible QP; ``tau`` solves it with a fresh workspace of the
    #: configured backend.
    RESOLVED = "resolved"
    #: The QP was infeasible; ``tau`` solves it with the named limit group relaxed (and is
    #: clipped to the torque limits): the safest command while the robot is pushed hard.
    RELAXED = "relaxed"
    #: No usable solution (solver error, bad state, infeasible physics); ``tau`` is the safe
    #: fallback, the last good torques with joint damping.
    FALLBACK = "fallback"


@dataclass
class ControlOutput(MotorCommand):
    """The result of :meth:`wbc.WholeBodyController.step`. Never ``None``.

    It is a :class:`~wbc.robot_io.motor_command.MotorCommand` (``q_des``, ``dq_des``, ``kp``,
    ``kd``, ``tau_ff``, description order), the command a robot's motor drivers take, plus
    what the tick found.
    """

    #: The torque [N m] (12,) the command gives at the measured state, clipped at the
    #: effort limits: what a plant that takes bare torques should get.
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
    #: Stage durations [s]: ``model``, ``assembly``, ``solve``, ``total``.
    timings: dict[str, float] = field(default_factory=dict)

    @classmethod
    def damped_hold(cls, tau_good: np.ndarray, v: np.ndarray, *, damping: float,
                    tau_max: np.ndarray, message: str, elapsed_s: float, contacts: int,
                    group: str = "", q_joints: np.ndarray | None = None) -> ControlOutput:
        """The safe fallback: the last good torques with joint damping, inside the limits.

        As a motor command: ``tau_ff`` the last good torques, ``kd = damping`` towards zero
        velocity, ``kp = 0`` (``q_des`` is the last measured position, or zero, and unused).
        Non-finite joint velocities (a broken sensor) are taken as zero in ``tau``; the
        ``contacts`` forces are NaN (unknown).
        """
        n = len(tau_good)
        v = np.asarray(v, dtype=float).reshape(-1)
        vj = np.zeros(n)
        if v.shape == (n + 6,):
            vj = np.where(np.isfinite(v[6:]), v[6:], 0.0)
        tau_ff = np.clip(tau_good, -tau_max, tau_max)
        tau = np.clip(tau_ff - damping * vj, -tau_max, tau_max)
        q_des = np.zeros(n)
        if q_joints is not None and np.isfinite(q_joints).all():
            q_des[:] = q_joints
        return cls(q_des=q_des, dq_des=np.zeros(n), kp=np.zeros(n), kd=np.full(n, damping),
                   tau_ff=tau_ff, tau=tau, qdd=np.full(n + 6, np.nan),
                   forces=np.full((contacts, 3), np.nan), status=ControlStatus.FALLBACK,
                   message=message, infeasible_group=group, timings={"total": elapsed_s})

    @property
    def ok(self) -> bool:
        """True when the QP was solved."""
        return self.status is ControlStatus.OK
