"""The GO2's low-level motor command: desired position and velocity, PD gains, feed-forward torque."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class MotorCommand:
    """One command per joint, as the GO2's motor drivers take it (12 joints, one order).

    Each driver closes its own loop at its own rate (10 to 20 kHz on the GO2) on

        ``tau = tau_ff + kp (q_des - q) + kd (dq_des - dq)``, clipped at the effort limit,

    so the feed-forward torque carries the whole-body plan and the PD terms correct what
    the plan's model did not know (joint friction, damping, rotor inertia) between ticks.
    ``kp = kd = 0`` is pure torque control.

    Arrays are (12,) in one joint order: the description's (FL, FR, RL, RR x hip, thigh,
    calf) when it comes from a controller; a robot's own order after :meth:`reordered`.
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

    @classmethod
    def pure_torque(cls, tau: np.ndarray) -> MotorCommand:
        """A command that applies ``tau`` [N m] whatever the state (zero gains)."""
        tau = np.asarray(tau, dtype=float)
        zeros = np.zeros_like(tau)
        return cls(q_des=zeros, dq_des=zeros.copy(), kp=zeros.copy(), kd=zeros.copy(),
                   tau_ff=tau.copy())

    def torque_at(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The torque [N m] the drivers apply at joint positions ``q`` and velocities ``dq``.

        Unclipped: the effort limit is the driver's, see :meth:`clipped_torque_at`.
        """
        return self.tau_ff + self.kp * (self.q_des - q) + self.kd * (self.dq_des - dq)

    def clipped_torque_at(self, q: np.ndarray, dq: np.ndarray,
                          effort_limit: np.ndarray) -> np.ndarray:
        """:meth:`torque_at`, clipped at ``effort_limit`` [N m] as a motor driver saturates."""
        return np.clip(self.torque_at(q, dq), -effort_limit, effort_limit)

    def reordered(self, index: np.ndarray) -> MotorCommand:
        """The same command with its arrays taken at ``index`` (``new[i] = old[index[i]]``)."""
        return MotorCommand(q_des=self.q_des[index], dq_des=self.dq_des[index],
                            kp=self.kp[index], kd=self.kd[index], tau_ff=self.tau_ff[index])

    def copy(self) -> MotorCommand:
        """A command with its own arrays."""
        return self.reordered(np.arange(len(self.tau_ff)))

    def problems(self, effort_limit: np.ndarray, names: tuple[str, ...] | None = None) -> str:
        """Why a driver should refuse this command ('' when it is fine).

        Refused: a wrong shape, a non-finite value, a negative gain, or a feed-forward
        torque beyond ``effort_limit`` [N m]. Joints are named by ``names`` when given, else
        by index.
        """
        def joints(mask: np.ndarray) -> list:
            found = np.flatnonzero(mask).tolist()
            return [names[i] for i in found] if names is not None else found

        n = len(effort_limit)
        fields = {"q_des": self.q_des, "dq_des": self.dq_des, "kp": self.kp, "kd": self.kd,
                  "tau_ff": self.tau_ff}
        for name, values in fields.items():
            values = np.asarray(values)
            if values.shape != (n,):
                return f"{name}: expected shape ({n},), received {values.shape}"
            if not np.isfinite(values).all():
                return f"{name}: non-finite at joints {joints(~np.isfinite(values))}"
        for name in ("kp", "kd"):
            if (fields[name] < 0.0).any():
                return f"{name}: negative gain at joints {joints(fields[name] < 0.0)}"
        beyond = np.abs(self.tau_ff) > effort_limit
        if beyond.any():
            return f"tau_ff: beyond the effort limits at joints {joints(beyond)}"
        return ""
