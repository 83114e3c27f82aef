"""From a solved tick to the motor drivers' command: desired joint state, gains, feed-forward."""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple, TypedDict

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


class MotorArrays(TypedDict):
    """One tick's command arrays (joints in the description's order), as
    :class:`~wbc.controller.control_output.ControlOutput` takes them by keyword."""

    q_des: np.ndarray
    dq_des: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    tau_ff: np.ndarray
    tau: np.ndarray


class JointShaping(NamedTuple):
    """The shaper's per-joint numbers (joints,), built once and changed in place (``kp``,
    ``kd`` with the legs' stance, the rest by :meth:`MotorCommandShaper.retune`): a compiled
    call bound to them never needs binding again."""

    #: Known joint damping [N m s/rad] and friction [N m] added along ``dq_des``.
    damping: np.ndarray
    friction: np.ndarray
    #: The controller's torque limits [N m]: ``tau_ff`` stays inside.
    tau_max: np.ndarray
    #: The motors' effort limits [N m]: ``tau`` is clipped there.
    effort_limit: np.ndarray
    kp: np.ndarray
    kd: np.ndarray
    #: The friction's tanh velocity scale [rad/s] (one value for every joint).
    velocity_scale: np.ndarray


class ReferenceState(NamedTuple):
    """The :class:`JointReference`'s desired state (in/out) [rad], [rad/s] and its bounds
    (joints,) [rad], [rad/s] (the reference's one value for every joint)."""

    q_des: np.ndarray
    dq_des: np.ndarray
    max_position_error: np.ndarray
    max_velocity_error: np.ndarray


#: The inputs (measured state, QP outputs): any float64 vector, read-only or not.
_INPUT = numba.types.Array(numba.types.float64, 1, "A", readonly=True)


@numba.njit(cache=True)
def _shape(joints, reference, keep, dt, q, dq, qdd, tau_qp, out):  # pragma: no cover
    """Advance the joint reference (as :meth:`JointReference.advance`) over ``dt`` [s] from
    the measured ``q``, ``dq`` and the QP's ``qdd``, ``tau_qp``, and fill the command rows
    ``out = [q_des, dq_des, kp, kd, tau_ff, tau]`` (6, n).

    Args:
        joints: :class:`JointShaping`.
        reference: :class:`ReferenceState` (``q_des``, ``dq_des`` advanced in place).
        keep: This period's decay factors (:meth:`JointReference.prepare`).
    """
    q_ref, dq_ref = reference.q_des, reference.dq_des
    max_position_error, max_velocity_error = (reference.max_position_error,
                                              reference.max_velocity_error)
    damping, friction, tau_max = joints.damping, joints.friction, joints.tau_max
    kp, kd, effort_limit = joints.kp, joints.kd, joints.effort_limit
    velocity_scale = joints.velocity_scale
    for i in range(q.size):
        qr = q[i] + keep[i] * (q_ref[i] - q[i])
        dqr = dq[i] + keep[i] * (dq_ref[i] - dq[i]) + dt * qdd[i]
        dqr = dq[i] + min(max(dqr - dq[i], -max_velocity_error[i]), max_velocity_error[i])
        qr += dt * dqr
        qr = q[i] + min(max(qr - q[i], -max_position_error[i]), max_position_error[i])
        q_ref[i], dq_ref[i] = qr, dqr
        tau_ff = tau_qp[i]
        if damping[i] != 0.0 or friction[i] != 0.0:
            tau_ff += damping[i] * dqr + friction[i] * np.tanh(dqr / velocity_scale[i])
            tau_ff = min(max(tau_ff, -tau_max[i]), tau_max[i])
        tau = tau_ff + kp[i] * (qr - q[i]) + kd[i] * (dqr - dq[i])
        out[0, i], out[1, i], out[2, i], out[3, i] = qr, dqr, kp[i], kd[i]
        out[4, i] = tau_ff
        out[5, i] = min(max(tau, -effort_limit[i]), effort_limit[i])


def _bind_shape(joints: JointShaping, reference: ReferenceState) -> Callable[..., None]:
    """:func:`_shape`'s compiled overload (from numba's cache, else compiled now rather than
    at the first tick) with the shaper's own groups bound: ``(keep, dt, q, dq, qdd, tau_qp,
    out)`` per call, without the dispatcher's typing of every argument (the groups' would
    cost a microsecond a call)."""
    signature = (numba.typeof(joints), numba.typeof(reference), numba.float64[::1],
                 numba.float64, _INPUT, _INPUT, _INPUT, _INPUT, numba.float64[:, ::1])
    return functools.partial(_shape.compile(signature), joints, reference)


def _float_vector(values: np.ndarray) -> np.ndarray:
    """``values`` as the compiled shaping reads them: a float64 vector (itself when it is)."""
    if type(values) is np.ndarray and values.dtype == np.float64 and values.ndim == 1:
        return values
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1:
        raise ConfigurationError(f"expected a vector of joint values, received shape "
                                 f"{array.shape}")
    return array


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
        self._stance = np.ones(n, dtype=bool)
        self._out_shape = (6, n)
        reference = self.reference
        self._joints = JointShaping(self._damping, self._friction, self.tau_max,
                                    self.effort_limit, self.kp, self.kd, np.empty(n))
        self._reference = ReferenceState(reference.q_des, reference.dq_des, np.empty(n),
                                         np.empty(n))
        self._fill_scalars()
        self._shape = _bind_shape(self._joints, self._reference)
        #: The rows ``[q_des, dq_des, kp, kd, tau_ff, tau]`` (6, joints) that
        #: :meth:`compiled_step` writes (overwritten each tick: :meth:`command` copies them).
        self.command_rows = np.zeros(self._out_shape)

    def _fill_scalars(self) -> None:
        """The settings' and the reference's scalars into the per-joint arrays the compiled
        shaping reads (in place: every call bound to them stays bound)."""
        self._joints.velocity_scale[:] = float(self.settings.friction_velocity_scale_rad_s)
        self._reference.max_position_error[:] = self.reference.max_position_error
        self._reference.max_velocity_error[:] = self.reference.max_velocity_error

    def retune(self, settings: ShapingSettings) -> None:
        """Take the gains, leaks and reference bounds of ``settings`` (a walk's faster swing
        tracking, and back), each joint keeping its stance or swing; the known friction
        stays as built."""
        self.settings = settings
        self.reference.max_position_error = settings.reference_position_bound_rad
        self.reference.max_velocity_error = settings.reference_velocity_bound_rad_s
        for stance in (True, False):
            self.set_stance(np.flatnonzero(self._stance == stance).tolist(), stance)
        self._fill_scalars()

    def set_stance(self, joints: Sequence[int], stance: bool) -> None:
        """Give a leg's joints (their indices) the stance or the swing gains and leak."""
        cfg = self.settings
        joints = list(joints)
        self._stance[joints] = stance
        self.kp[joints] = cfg.stance_kp if stance else cfg.swing_kp
        self.kd[joints] = cfg.stance_kd if stance else cfg.swing_kd
        self.reference.set_leak_time(
            joints, cfg.stance_leak_time_s if stance else cfg.swing_leak_time_s)

    def shape(self, q: np.ndarray, dq: np.ndarray, qdd: np.ndarray,
              tau_qp: np.ndarray) -> MotorArrays:
        """The command's arrays (new ones, owned by the caller) for one solved tick.

        Args:
            q: Measured joint positions [rad] (joints,).
            dq: Measured joint velocities [rad/s] (joints,).
            qdd: The QP's joint accelerations [rad/s^2] (joints,).
            tau_qp: The QP's joint torques [N m] (joints,).
        """
        reference, dt = self.reference, self.control_period_s
        keep = reference.prepare(q, dq, dt)
        out = np.empty(self._out_shape)  # the command owns its arrays: one block, six views
        self._shape(keep, dt, _float_vector(q), _float_vector(dq), _float_vector(qdd),
                    _float_vector(tau_qp), out)
        return {"q_des": out[0], "dq_des": out[1], "kp": out[2], "kd": out[3],
                "tau_ff": out[4], "tau": out[5]}

    def compiled_step(self, q: np.ndarray, dq: np.ndarray, qdd: np.ndarray,
                      tau_qp: np.ndarray) -> tuple[Any, tuple]:
        """:meth:`shape` as a step of a :class:`~wbc.core.compiled_program.CompiledProgram`
        (the controller's compiled solve runs it after accepting the solution), writing
        :attr:`command_rows`. Call :meth:`prepare` before each run.

        Args:
            q, dq, qdd, tau_qp: As :meth:`shape` takes them: float64 vectors (joints,) that
                stay the same objects, updated in place by the caller before each run.
        """
        return _shape, (self._joints, self._reference, self.reference.decay,
                        self.control_period_s, q, dq, qdd, tau_qp, self.command_rows)

    def prepare(self, q: np.ndarray, dq: np.ndarray) -> None:
        """Before a run of :meth:`compiled_step`: anchor the reference at the measured
        joint state [rad], [rad/s] if it was released, and its decay factors for the
        period (:meth:`JointReference.prepare`)."""
        self.reference.prepare(q, dq, self.control_period_s)

    def command(self) -> tuple[np.ndarray, ...]:
        """The command :meth:`compiled_step` last wrote: ``q_des, dq_des, kp, kd, tau_ff,
        tau`` (new arrays, owned by the caller; :meth:`shape`'s, in its order)."""
        out = self.command_rows.copy()  # one block; its rows by index (iterating is slower)
        return out[0], out[1], out[2], out[3], out[4], out[5]
