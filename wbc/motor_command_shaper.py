"""From a solved tick to the motor drivers' command: desired joint state, per-leg gains, feed-forward."""

from __future__ import annotations

import numpy as np

from wbc.controller_config import ControllerConfig
from wbc.description import LEGS
from wbc.joint_reference import JointReference

_NJ = 12
#: Joint-type index (0 hip, 1 thigh, 2 calf) of each joint, description order.
_JOINT_TYPE = np.tile(np.arange(3), len(LEGS))


class MotorCommandShaper:
    """Builds the :class:`~wbc.motor_command.MotorCommand` of a tick both controllers share.

    - ``q_des``, ``dq_des``: the QP's joint accelerations integrated by a
      :class:`JointReference`, bounded around the measured state;
    - ``kp``, ``kd``: the config's stance or swing gains, per leg;
    - ``tau_ff``: the QP's torques, plus the known joint friction along the desired velocity
      (``known_joint_damping dq_des + known_joint_friction tanh(dq_des / scale)``), inside
      the controller's torque limits;
    - ``tau``: what that command gives at the measured state, clipped at the effort limits.
    """

    def __init__(self, config: ControllerConfig, *, tau_max: np.ndarray,
                 effort_limit: np.ndarray):
        """Args:
            config: Gains, bounds and the known joint friction.
            tau_max: The controller's torque limits [N m] (12,): ``tau_ff`` stays inside.
            effort_limit: The motors' effort limits [N m] (12,): ``tau`` is clipped at them.
        """
        self.config = config
        self.reference = JointReference(
            _NJ, max_position_error_rad=config.reference_position_bound_rad,
            max_velocity_error_rad_s=config.reference_velocity_bound_rad_s,
            leak_time_s=config.stance_leak_time_s)
        self.tau_max = tau_max
        self.effort_limit = effort_limit
        self._damping = np.asarray(config.known_joint_damping)[_JOINT_TYPE]
        self._friction = np.asarray(config.known_joint_friction)[_JOINT_TYPE]
        self._compensate = bool(self._damping.any() or self._friction.any())
        self.kp = np.full(_NJ, config.stance_kp)
        self.kd = np.full(_NJ, config.stance_kd)

    def set_stance(self, leg_index: int, stance: bool) -> None:
        """Give a leg's three joints the stance or the swing gains."""
        cfg = self.config
        joints = slice(3 * leg_index, 3 * leg_index + 3)
        self.kp[joints] = cfg.stance_kp if stance else cfg.swing_kp
        self.kd[joints] = cfg.stance_kd if stance else cfg.swing_kd
        self.reference.set_leak_time(
            joints, cfg.stance_leak_time_s if stance else cfg.swing_leak_time_s)

    def shape(self, q: np.ndarray, dq: np.ndarray, qdd: np.ndarray,
              tau_qp: np.ndarray) -> dict[str, np.ndarray]:
        """The command's arrays (new ones, owned by the caller) for one solved tick.

        Args:
            q: Measured joint positions [rad] (12,).
            dq: Measured joint velocities [rad/s] (12,).
            qdd: The QP's joint accelerations [rad/s^2] (12,).
            tau_qp: The QP's joint torques [N m] (12,).
        """
        reference = self.reference
        reference.advance(q, dq, qdd, self.config.control_period_s)
        q_des, dq_des = reference.q_des.copy(), reference.dq_des.copy()
        tau_ff = tau_qp.copy()
        if self._compensate:
            tau_ff += self._damping * dq_des
            tau_ff += self._friction * np.tanh(dq_des / self.config.friction_velocity_scale_rad_s)
            np.clip(tau_ff, -self.tau_max, self.tau_max, out=tau_ff)
        kp, kd = self.kp.copy(), self.kd.copy()
        tau = tau_ff + kp * (q_des - q) + kd * (dq_des - dq)
        np.clip(tau, -self.effort_limit, self.effort_limit, out=tau)
        return {"q_des": q_des, "dq_des": dq_des, "kp": kp, "kd": kd, "tau_ff": tau_ff,
                "tau": tau}
