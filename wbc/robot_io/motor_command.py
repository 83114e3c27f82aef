"""The GO2's motor command: desired joint position and velocity, PD gains, feed-forward torque."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from wbc.model.orders import DESCRIPTION_ORDERS, Orders

_VECTOR = numba.float64[:]


@numba.njit(numba.boolean(_VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR), cache=True)
def command_fine(q_des, dq_des, kp, kd, tau_ff, effort_limit):
    """True when a driver takes the command: shapes (n,), finite, gains >= 0, |tau_ff| <= limit
    (compiled: the simulated drivers call it inside their own compiled write)."""
    n = effort_limit.shape[0]
    if (q_des.shape[0] != n or dq_des.shape[0] != n or kp.shape[0] != n or kd.shape[0] != n
            or tau_ff.shape[0] != n):
        return False
    for i in range(n):
        if not (math.isfinite(q_des[i]) and math.isfinite(dq_des[i]) and math.isfinite(kp[i])
                and math.isfinite(kd[i]) and math.isfinite(tau_ff[i])
                and kp[i] >= 0.0 and kd[i] >= 0.0 and abs(tau_ff[i]) <= effort_limit[i]):
            return False
    return True


@numba.njit(numba.boolean(_VECTOR, _VECTOR), cache=True)
def _within(values, limit):
    """Same shape, a finite sum and every ``|values| <= limit``."""
    n = limit.shape[0]
    if values.shape[0] != n:
        return False
    total = 0.0
    for i in range(n):
        total += values[i]
        if not abs(values[i]) <= limit[i]:
            return False
    return math.isfinite(total)


@numba.njit(numba.boolean(_VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR),
            cache=True)
def command_and_torque_fine(q_des, dq_des, kp, kd, tau_ff, tau,
                            effort_limit):  # pragma: no cover - compiled
    """:func:`command_fine` and ``tau`` within the limits (:func:`within_effort_limits`) in
    one compiled call: a control loop's check of a command before it sends it."""
    return (command_fine(q_des, dq_des, kp, kd, tau_ff, effort_limit)
            and _within(tau, effort_limit))


def within_effort_limits(tau: np.ndarray, effort_limit: np.ndarray) -> bool:
    """Whether ``tau`` [N m] has the limits' shape, is finite and is inside ``+-effort_limit``.

    Compiled for float64 vectors (no allocation); anything else is checked with NumPy.
    """
    try:
        return _within(tau, effort_limit)
    except TypeError:  # not two float64 vectors
        tau = np.asarray(tau)
        limit = np.asarray(effort_limit)
        return bool(tau.shape == limit.shape and math.isfinite(tau.sum())
                    and np.all(np.abs(tau) <= limit))


@dataclass
class MotorCommand:
    """One command per joint, as the GO2's motor drivers take it (12 joints, one order).

    Each driver closes its own loop at its own rate (10 to 20 kHz on the GO2) on

        ``tau = tau_ff + kp (q_des - q) + kd (dq_des - dq)``, clipped at the effort limit,

    so the feed-forward torque carries the whole-body plan and the PD terms correct what
    the plan's model did not know (joint friction, damping, rotor inertia) between ticks.
    ``kp = kd = 0`` is pure torque control.

    Arrays are (12,) in one joint order, :attr:`orders`: the description's (FL, FR, RL, RR x
    hip, thigh, calf) when it comes from a controller; a robot's own order after
    :meth:`reordered`. A command built without ``orders`` is in the description's, as every
    command a controller makes; the conversions to another order
    (:meth:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand.from_control_output`,
    :class:`actions.MappedRobot`) check it, so that a command already in a robot's order is
    refused rather than reordered a second time.
    """

    #: Desired joint positions [rad].
    q_des: np.ndarray
    #: Desired joint velocities [rad/s].
    dq_des: np.ndarray
    #: Position gains [N m/rad].
    kp: np.ndarray
    #: Velocity gains [N m s/rad].
    kd: np.ndarray
    #: Feed-forward torques [N m].
    tau_ff: np.ndarray
    #: The joint order of the arrays (its legs unused: a command has no foot array).
    orders: Orders = field(default=DESCRIPTION_ORDERS, kw_only=True)

    @classmethod
    def pure_torque(cls, tau: np.ndarray, *, orders: Orders = DESCRIPTION_ORDERS
                    ) -> MotorCommand:
        """A command that applies ``tau`` [N m] (in ``orders``) whatever the state (zero
        gains)."""
        tau = np.asarray(tau, dtype=float)
        zeros = np.zeros_like(tau)
        return cls(q_des=zeros, dq_des=zeros.copy(), kp=zeros.copy(), kd=zeros.copy(),
                   tau_ff=tau.copy(), orders=orders)

    def torque_at(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The torque [N m] the drivers apply at joint positions ``q`` and velocities ``dq``.

        Unclipped: the effort limit is the driver's, see :meth:`clipped_torque_at`.
        """
        return self.tau_ff + self.kp * (self.q_des - q) + self.kd * (self.dq_des - dq)

    def clipped_torque_at(self, q: np.ndarray, dq: np.ndarray,
                          effort_limit: np.ndarray) -> np.ndarray:
        """:meth:`torque_at`, clipped at ``effort_limit`` [N m] as a motor driver saturates."""
        return np.clip(self.torque_at(q, dq), -effort_limit, effort_limit)

    def reordered(self, index: np.ndarray, *, orders: Orders | None = None) -> MotorCommand:
        """The same command with its arrays taken at ``index`` (``new[i] = old[index[i]]``).

        Args:
            index: Where each joint of the result is in this command.
            orders: The result's orders, from a caller that built ``index`` for them (a
                :class:`~wbc.model.joint_map.JointMap` of a robot's names); by default this
                command's joint names taken at ``index``.
        """
        return MotorCommand(q_des=self.q_des[index], dq_des=self.dq_des[index],
                            kp=self.kp[index], kd=self.kd[index], tau_ff=self.tau_ff[index],
                            orders=self.orders.reordered(index) if orders is None else orders)

    def copy(self) -> MotorCommand:
        """A command with its own arrays (a plain :class:`MotorCommand`), same orders."""
        return MotorCommand(q_des=np.array(self.q_des), dq_des=np.array(self.dq_des),
                            kp=np.array(self.kp), kd=np.array(self.kd),
                            tau_ff=np.array(self.tau_ff), orders=self.orders)

    def problems(self, effort_limit: np.ndarray, names: tuple[str, ...] | None = None) -> str:
        """Why a driver should refuse this command ('' when it is fine).

        Refused: a wrong shape, a non-finite value, a negative gain, or a feed-forward
        torque beyond ``effort_limit`` [N m]. Joints are named by ``names`` when given, else
        by index. A good command of float64 vectors is checked without allocating.
        """
        try:
            if command_fine(self.q_des, self.dq_des, self.kp, self.kd, self.tau_ff,
                             effort_limit):
                return ""
        except TypeError:  # not float64 vectors: the checks below say what is wrong
            pass

        def joints(mask: np.ndarray) -> list:
            found = np.flatnonzero(mask).tolist()
            return [names[i] for i in found] if names is not None else found

        n = len(effort_limit)
        fields = {"q_des": self.q_des, "dq_des": self.dq_des, "kp": self.kp, "kd": self.kd,
                  "tau_ff": self.tau_ff}
        for name, values in fields.items():
            values = fields[name] = np.asarray(values)
            if values.shape != (n,):
                return f"{name}: expected shape ({n},), received {values.shape}"
            if not np.isfinite(values).all():
                return f"{name}: non-finite at joints {joints(~np.isfinite(values))}"
        for name in ("kp", "kd"):
            if (fields[name] < 0.0).any():
                return f"{name}: negative gain at joints {joints(fields[name] < 0.0)}"
        beyond = np.abs(fields["tau_ff"]) > effort_limit
        if beyond.any():
            return f"tau_ff: beyond the effort limits at joints {joints(beyond)}"
        return ""
