"""From a solved tick to the motor drivers' command: desired joint state, gains, feed-forward."""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np

from wbc.controller.controller_config import ShapingSettings
from wbc.controller.joint_reference import JointReference
from wbc.core.errors import ConfigurationError

#: The joint types of the per-joint-type settings, in their order.
JOINT_TYPES = ("hip", "thigh", "calf")


def joint_types(joint_names: Sequence[str]) -> list[int]:
    """Each joint's type (0 hip, 1 thigh, 2 calf), from its name (``FR_thigh_joint``)."""
    return [JOINT_TYPES.index(name.split("_")[1]) for name in joint_names]


#: The inputs (measured state, QP outputs): any float64 vector, read-only or not.
_INPUT = numba.types.Array(numba.types.float64, 1, "A", readonly=True)
_OWN, _F8 = numba.types.float64[::1], numba.types.float64


# An explicit signature: compiled (or read from numba's cache) at import rather than at the
# first tick, which it would stall for milliseconds. The shaper's own arrays are
# C-contiguous.
@numba.njit(numba.types.void(_INPUT, _INPUT, _INPUT, _INPUT, _F8, _OWN, _F8, _F8, _OWN, _OWN,
                             _OWN, _OWN, _F8, _OWN, _OWN, _OWN, _OWN,
                             numba.types.float64[:, ::1]), cache=True)
def _shape(q, dq, qdd, tau_qp, dt, keep, max_position_error, max_velocity_error, q_ref,
           dq_ref, damping, friction, velocity_scale, tau_max, kp, kd, effort_limit, out):
    """Advance the joint reference (as :meth:`JointReference.advance`) and fill the command
    rows ``out = [q_des, dq_des, kp, kd, tau_ff, tau]`` (6, n)."""
    for i in range(q.size):
        qr = q[i] + keep[i] * (q_ref[i] - q[i])
        dqr = dq[i] + keep[i] * (dq_ref[i] - dq[i]) + dt * qdd[i]
        dqr = dq[i] + min(max(dqr - dq[i], -max_velocity_error), max_velocity_error)
        qr += dt * dqr
        qr = q[i] + min(max(qr - q[i], -max_position_error), max_position_error)
        q_ref[i], dq_ref[i] = qr, dqr
        tau_ff = tau_qp[i]
        if damping[i] != 0.0 or friction[i] != 0.0:
            tau_ff += damping[i] * dqr + friction[i] * np.tanh(dqr / velocity_scale)
            tau_ff = min(max(tau_ff, -tau_max[i]), tau_max[i])
        tau = tau_ff + kp[i] * (qr - q[i]) + kd[i] * (dqr - dq[i])
        out[0, i], out[1, i], out[2, i], out[3, i] = qr, dqr, kp[i], kd[i]
        out[4, i] = tau_ff
        out[5, i] = min(max(tau, -effort_limit[i]), effort_limit[i])


class MotorCommandShaper:
    """Builds the :class:`~wbc.robot_io.motor_command.MotorCommand` of a tick (both
    controllers share it).

    - ``q_des``, ``dq_des``: the QP's joint accelerations integrated by a
      :class:`JointReference`, bounded around the measured state;
    - ``kp``, ``kd``: the config's stance or swing gains, per leg;
    - ``tau_ff``: the QP's torques, plus the known joint friction along the desired velocity
      (``known_joint_damping dq_des + known_joint_friction tanh(dq_des / scale)``), inside
      the controller's torque limits;
    - ``tau``: what that command gives at the measured state, clipped at the effort limits.
    """

    def __init__(self, settings: ShapingSettings, *, control_period_s: float,
                 tau_max: np.ndarray, effort_limit: np.ndarray, joint_types: Sequence[int]):
        """Args:
            settings: Gains, bounds, leaks and the known joint friction (a
                :class:`ControllerConfig`'s ``shaping``).
            control_period_s: How far ahead the reference is integrated [s].
            tau_max: The controller's torque limits [N m] (joints,): ``tau_ff`` stays inside.
            effort_limit: The motors' effort limits [N m] (joints,): ``tau`` is clipped there.
            joint_types: Each joint's type, 0 hip, 1 thigh, 2 calf (the index into the
                per-joint-type friction values).
        """
        self.settings = settings
        self.control_period_s = float(control_period_s)
        types = np.asarray(joint_types, dtype=np.int64)
        n = types.size
        if np.shape(tau_max) != (n,) or np.shape(effort_limit) != (n,) or np.any(types < 0) \
                or np.any(types > 2):
            raise ConfigurationError(
                f"joint_types: expected {n} types in 0..2 and limits of {n} joints each, "
                f"received types {types.tolist()}, tau_max {np.shape(tau_max)} and "
                f"effort_limit {np.shape(effort_limit)}")
        self.reference = JointReference(
            n, max_position_error_rad=settings.reference_position_bound_rad,
            max_velocity_error_rad_s=settings.reference_velocity_bound_rad_s,
            leak_time_s=settings.stance_leak_time_s)
        # Float64, C-contiguous, as the compiled shaping takes them: the caller's own arrays
        # when they already are (a caller that shares them with its QP keeps sharing).
        self.tau_max = np.ascontiguousarray(tau_max, dtype=float)
        self.effort_limit = np.ascontiguousarray(effort_limit, dtype=float)
        self._damping = np.asarray(settings.known_joint_damping, dtype=float)[types]
        self._friction = np.asarray(settings.known_joint_friction, dtype=float)[types]
        self.kp = np.full(n, settings.stance_kp)
        self.kd = np.full(n, settings.stance_kd)
        self._out_shape = (6, n)

    def set_stance(self, joints: Sequence[int], stance: bool) -> None:
        """Give a leg's joints (their indices) the stance or the swing gains and leak."""
        cfg = self.settings
        joints = list(joints)
        self.kp[joints] = cfg.stance_kp if stance else cfg.swing_kp
        self.kd[joints] = cfg.stance_kd if stance else cfg.swing_kd
        self.reference.set_leak_time(
            joints, cfg.stance_leak_time_s if stance else cfg.swing_leak_time_s)

    def shape(self, q: np.ndarray, dq: np.ndarray, qdd: np.ndarray,
              tau_qp: np.ndarray) -> dict[str, np.ndarray]:
        """The command's arrays (new ones, owned by the caller) for one solved tick.

        Args:
            q: Measured joint positions [rad] (joints,).
            dq: Measured joint velocities [rad/s] (joints,).
            qdd: The QP's joint accelerations [rad/s^2] (joints,).
            tau_qp: The QP's joint torques [N m] (joints,).
        """
        reference, cfg, dt = self.reference, self.settings, self.control_period_s
        keep = reference.prepare(q, dq, dt)
        out = np.empty(self._out_shape)  # the command owns its arrays: one block, six views
        _shape(q, dq, qdd, tau_qp, dt, keep, reference.max_position_error,
               reference.max_velocity_error, reference.q_des, reference.dq_des, self._damping,
               self._friction, cfg.friction_velocity_scale_rad_s, self.tau_max, self.kp,
               self.kd, self.effort_limit, out)
        return {"q_des": out[0], "dq_des": out[1], "kp": out[2], "kd": out[3],
                "tau_ff": out[4], "tau": out[5]}
