"""The motor command's desired joint state: the QP's accelerations integrated, kept near the
measured state."""

from __future__ import annotations

import numpy as np

from wbc.core.validation import as_float


class JointReference:
    """``q_des`` and ``dq_des`` for the motor drivers' PD, from the QP's joint accelerations.

    Each tick the plan is integrated one control period ahead (semi-implicit Euler):

        ``dq_des += qdd dt``,  ``q_des += dq_des dt``

    and then pulled back to within a fixed distance of the measured state:

        ``|q_des - q| <= max_position_error``,  ``|dq_des - dq| <= max_velocity_error``.

    The integration is what makes the drivers' PD useful: where the plant lags the plan
    (joint friction, damping, rotor inertia the model lacks), the desired state runs ahead
    of the measured one and the PD pushes the joint after it, at the drivers' rate, without
    knowing why it lags. The bound is what keeps it from drifting: however long the plant
    lags (a leg blocked by the floor, a foot held by a hand), the PD can add at most
    ``kp max_position_error + kd max_velocity_error`` to the planned torque.
    """

    def __init__(self, n: int, *, max_position_error_rad: float,
                 max_velocity_error_rad_s: float, leak_time_s: float = 0.0):
        """Args:
            n: Number of joints.
            max_position_error_rad: Bound of ``|q_des - q|`` [rad].
            max_velocity_error_rad_s: Bound of ``|dq_des - dq|`` [rad/s].
        """
        self.max_position_error = as_float("max_position_error_rad", max_position_error_rad,
                                           low=0.0)
        self.max_velocity_error = as_float("max_velocity_error_rad_s",
                                           max_velocity_error_rad_s, low=0.0)
        #: Desired joint positions [rad].
        self.q_des = np.zeros(n)
        #: Desired joint velocities [rad/s].
        self.dq_des = np.zeros(n)
        self._leak_time = np.full(n, as_float("leak_time_s", leak_time_s, low=0.0))
        self._keep = np.ones(n)  # per-tick decay factors, for the period ``_keep_dt``
        self._keep_dt = 0.0
        self._anchored = False
        self._offset = np.zeros(n)

    @property
    def decay(self) -> np.ndarray:
        """The per-joint decay factors of the last :meth:`prepare`'s period (joints,): the
        same array every tick, updated in place."""
        return self._keep

    def set_leak_time(self, joints: slice | list[int], leak_time_s: float) -> None:
        """Time constant [s] with which these joints' desired state decays towards the
        measured one (0: no decay, only the bounds)."""
        self._leak_time[joints] = as_float("leak_time_s", leak_time_s, low=0.0)
        self._keep_dt = 0.0  # recompute the decay factors on the next advance

    def reset(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Start from the measured joint state [rad], [rad/s]."""
        np.copyto(self.q_des, q)
        np.copyto(self.dq_des, dq)
        self._anchored = True

    def release(self) -> None:
        """Forget the plan: the next :meth:`advance` starts from the measured state.

        For ticks whose command did not come from a solved QP (a fallback).
        """
        self._anchored = False

    def prepare(self, q: np.ndarray, dq: np.ndarray, dt: float) -> np.ndarray:
        """Anchor at the measured state if released; the per-joint decay factors for ``dt``.

        The first half of :meth:`advance`, for callers that integrate in compiled code.
        """
        if not self._anchored:
            self.reset(q, dq)
        if dt != self._keep_dt:  # the modes or the period changed: not on every tick
            leaking = self._leak_time > 0.0
            self._keep[:] = 1.0
            self._keep[leaking] = np.maximum(0.0, 1.0 - dt / self._leak_time[leaking])
            self._keep_dt = dt
        return self._keep

    def advance(self, q: np.ndarray, dq: np.ndarray, qdd: np.ndarray, dt: float) -> None:
        """Integrate the joint accelerations ``qdd`` [rad/s^2] over ``dt`` [s], then bound.

        Args:
            q: Measured joint positions [rad].
            dq: Measured joint velocities [rad/s].
            qdd: The QP's joint accelerations [rad/s^2].
            dt: Control period [s].
        """
        keep = self.prepare(q, dq, dt)
        q_des, dq_des, offset = self.q_des, self.dq_des, self._offset
        q_des -= q
        q_des *= keep
        q_des += q
        dq_des -= dq
        dq_des *= keep
        dq_des += dq
        dq_des += dt * qdd
        np.subtract(dq_des, dq, out=offset)
        np.clip(offset, -self.max_velocity_error, self.max_velocity_error, out=offset)
        np.add(dq, offset, out=dq_des)
        q_des += dt * dq_des
        np.subtract(q_des, q, out=offset)
        np.clip(offset, -self.max_position_error, self.max_position_error, out=offset)
        np.add(q, offset, out=q_des)
