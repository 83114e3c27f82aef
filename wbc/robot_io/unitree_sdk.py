"""The Unitree SDK's low-level messages (``rt/lowcmd``, ``rt/lowstate``) as NumPy, without the SDK.

Plain NumPy records with the layout of ``unitree_go.msg.dds_.LowCmd_`` and ``LowState_``
(unitree_sdk2 / unitree_sdk2py); ``unitree_sdk2py`` is never imported. The two methods that
touch a message (:meth:`SdkMotorCommand.write_to`, :meth:`SdkLowState.from_message`) only
read and set its attributes.

Joint orders (always mapped by name through :meth:`wbc.model.joint_map.JointMap.unitree_sdk`):

- SDK order, the motor slots 0 to 11 of both messages (legs FR, FL, RR, RL):
  ``FR_hip_joint, FR_thigh_joint, FR_calf_joint, FL_hip_joint, FL_thigh_joint,
  FL_calf_joint, RR_hip_joint, RR_thigh_joint, RR_calf_joint, RL_hip_joint,
  RL_thigh_joint, RL_calf_joint``. Slots 12 to 19 carry no GO2 motor.
- Description order, everywhere else in this library (legs FL, FR, RL, RR):
  ``FL_hip_joint, FL_thigh_joint, FL_calf_joint, FR_hip_joint, FR_thigh_joint,
  FR_calf_joint, RL_hip_joint, RL_thigh_joint, RL_calf_joint, RR_hip_joint,
  RR_thigh_joint, RR_calf_joint``.

:class:`SdkMotorCommand`, one ``motor_cmd`` entry per leg motor, arrays (12,) in SDK order:

- ``mode``: ``0x01`` enable (:data:`MODE_ENABLE`), ``0x00`` stop (:data:`MODE_STOP`).
- ``q`` [rad], ``dq`` [rad/s]: the driver's position and velocity targets.
- ``tau`` [N m]: feed-forward torque.
- ``kp`` [N m/rad], ``kd`` [N m s/rad]: gains, >= 0. The driver applies
  ``tau + kp (q - q_meas) + kd (dq - dq_meas)``.
- With ``kp = 0`` the SDK's examples send ``q = PosStopF`` (:data:`POS_STOP_F`, 2.146e9),
  with ``kd = 0`` ``dq = VelStopF`` (:data:`VEL_STOP_F`, 16000.0): "no target".

:class:`SdkLowState`, what this library reads from ``LowState_``:

- ``imu_quaternion_wxyz`` (4,): base orientation ``R_world_base`` as ``(w, x, y, z)``,
  scalar first (``imu_state.quaternion``). Pinocchio stores ``(x, y, z, w)``.
- ``gyroscope_rad_s`` (3,) [rad/s]: base angular velocity in the base frame.
- ``accelerometer_m_s2`` (3,) [m/s^2]: specific force in the base frame (+9.81 along the
  base z axis when the robot stands still and level).
- ``q`` [rad], ``dq`` [rad/s], ``tau_est`` [N m]: per motor, (12,) SDK order
  (``motor_state[i].q``, ``.dq``, ``.tau_est``).
- ``foot_force`` (4,): raw sensor counts (int16 in the message, no unit), legs FR, FL, RR,
  RL (SDK leg order).

Not kept: ``imu_state.rpy`` (the quaternion's angles), ``motor_state[i].ddq``, and the
base position and linear velocity, which the robot does not measure: the state estimator
(:class:`wbc.StateEstimator`) provides them from :meth:`SdkLowState.sensor_record` (or
:func:`sensor_record_from_message`, which lets a failing sensor's NaN through to it)::

    estimator.reset(sensor_record_from_message(first_low_state))
    estimate = estimator.update(sensor_record_from_message(low_state), bounds)
    out = controller.step(estimate.q, estimate.v)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from wbc.core.conventions import NQ, NV, mujoco_to_pin, pin_to_mujoco
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS
from wbc.model.joint_map import JointMap
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord

#: ``motor_cmd[i].mode`` of a motor that follows its command.
MODE_ENABLE = 0x01
#: ``motor_cmd[i].mode`` of a motor that applies no torque.
MODE_STOP = 0x00
#: The SDK's ``PosStopF``: the position target of a motor with no position term (kp = 0).
POS_STOP_F = 2.146e9
#: The SDK's ``VelStopF``: the velocity target of a motor with no velocity term (kd = 0).
VEL_STOP_F = 16000.0
#: Motor slots in ``LowCmd_.motor_cmd`` and ``LowState_.motor_state``.
SDK_MOTOR_SLOTS = 20
#: Slots 0 to 11 are the GO2's leg motors.
SDK_LEG_MOTORS = 12
#: Gravity [m/s^2], Pinocchio's default: what the accelerometer reads at rest.
GRAVITY_M_S2 = 9.81

_SDK = JointMap.unitree_sdk()
# Messages carry float32: recognise a sentinel that went through one.
_SENTINEL_RTOL = 1e-6
_MIN_QUATERNION_NORM = 1e-6
_COMMAND_FIELDS = ("mode", "q", "dq", "tau", "kp", "kd")


def _joints(indices: np.ndarray, names: tuple[str, ...]) -> str:
    return ", ".join(f"{i} ({names[i]})" for i in indices)


def _gains(name: str, value: Any, names: tuple[str, ...]) -> np.ndarray:
    gains = as_vector(name, value, SDK_LEG_MOTORS)
    bad = np.flatnonzero(gains < 0.0)
    if len(bad):
        raise ConfigurationError(
            f"{name}: expected gains >= 0, received {gains[bad].tolist()} at "
            f"{_joints(bad, names)}"
        )
    return gains


def _modes(value: Any) -> np.ndarray:
    try:
        modes = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(
            f"mode: expected {SDK_LEG_MOTORS} values 0x00 (stop) or 0x01 (enable), "
            f"received {value!r}"
        ) from err
    if modes.shape != (SDK_LEG_MOTORS,):
        raise ConfigurationError(
            f"mode: expected an array of shape ({SDK_LEG_MOTORS},), received shape {modes.shape}"
        )
    bad = np.flatnonzero((modes != MODE_STOP) & (modes != MODE_ENABLE))
    if len(bad):
        raise ConfigurationError(
            f"mode: expected 0x00 (stop) or 0x01 (enable), received {modes[bad].tolist()} at "
            f"slots {_joints(bad, UNITREE_SDK_JOINT_NAMES)}"
        )
    return modes.astype(np.uint8)  # the message's type


def _is_stop(values: np.ndarray, sentinel: float) -> np.ndarray:
    return np.isclose(values, sentinel, rtol=_SENTINEL_RTOL, atol=0.0)


def _unit_quaternion(name: str, quat: np.ndarray, order: str) -> np.ndarray:
    norm = float(np.linalg.norm(quat))
    if norm < _MIN_QUATERNION_NORM:
        raise ConfigurationError(
            f"{name}: expected a unit quaternion ({order}), received {quat.tolist()} "
            f"(norm {norm:g}; a norm of at least {_MIN_QUATERNION_NORM:g} is normalised)"
        )
    return quat / norm


@dataclass
class SdkMotorCommand:
    """The 12 leg entries of ``LowCmd_.motor_cmd``, SDK order (FR, FL, RR, RL).

    Arrays are (12,) and copied on construction. See the module docstring for the fields,
    units and sentinels; build one from a controller with :meth:`from_control_output`.

    Example:
        >>> sdk_cmd = SdkMotorCommand.from_control_output(controller.step(...))
        >>> sdk_cmd.write_to(low_cmd)   # then the header fields and the CRC, and publish

    Raises:
        ConfigurationError: A wrong shape, a non-finite value, a negative gain, a mode other
            than 0x00 or 0x01, or a stop sentinel on a motor whose gain would act on it.
    """

    #: 0x01 enable, 0x00 stop (uint8).
    mode: np.ndarray
    #: Position targets [rad], or :data:`POS_STOP_F` where ``kp = 0``.
    q: np.ndarray
    #: Velocity targets [rad/s], or :data:`VEL_STOP_F` where ``kd = 0``.
    dq: np.ndarray
    #: Feed-forward torques [N m].
    tau: np.ndarray
    #: Position gains [N m/rad].
    kp: np.ndarray
    #: Velocity gains [N m s/rad].
    kd: np.ndarray

    def __post_init__(self) -> None:
        self.mode = _modes(self.mode)
        self.q = as_vector("q", self.q, SDK_LEG_MOTORS)
        self.dq = as_vector("dq", self.dq, SDK_LEG_MOTORS)
        self.tau = as_vector("tau", self.tau, SDK_LEG_MOTORS)
        self.kp = _gains("kp", self.kp, UNITREE_SDK_JOINT_NAMES)
        self.kd = _gains("kd", self.kd, UNITREE_SDK_JOINT_NAMES)
        # A sentinel is a target 2e9 rad away: only safe where no gain multiplies it.
        for name, target, sentinel, gain_name, gain in (
            ("q", self.q, POS_STOP_F, "kp", self.kp),
            ("dq", self.dq, VEL_STOP_F, "kd", self.kd),
        ):
            bad = np.flatnonzero(_is_stop(target, sentinel) & (gain > 0.0))
            if len(bad):
                raise ConfigurationError(
                    f"{name}: the stop sentinel {sentinel:g} with {gain_name} > 0 at slots "
                    f"{_joints(bad, UNITREE_SDK_JOINT_NAMES)}; the driver would chase it: "
                    f"use {gain_name} = 0 there, or a real target"
                )

    @classmethod
    def from_control_output(cls, cmd: MotorCommand, *,
                            use_stop_sentinels: bool = True) -> SdkMotorCommand:
        """The SDK command for a description-order command (a ``ControlOutput`` too).

        Every motor is enabled (``mode = 0x01``); the arrays are reordered by joint name.

        Args:
            cmd: The command, description order (FL, FR, RL, RR).
            use_stop_sentinels: Write :data:`POS_STOP_F` as ``q`` where ``kp = 0`` and
                :data:`VEL_STOP_F` as ``dq`` where ``kd = 0``, as the SDK's examples do
                (the targets are unused there). Off: the targets are sent as they are.

        Raises:
            ConfigurationError: A field of ``cmd`` (named ``cmd.<field>``) with a wrong
                shape, a non-finite value or a negative gain.
        """
        q_des = as_vector("cmd.q_des", cmd.q_des, SDK_LEG_MOTORS)
        dq_des = as_vector("cmd.dq_des", cmd.dq_des, SDK_LEG_MOTORS)
        tau_ff = as_vector("cmd.tau_ff", cmd.tau_ff, SDK_LEG_MOTORS)
        kp = _gains("cmd.kp", cmd.kp, JOINT_NAMES)
        kd = _gains("cmd.kd", cmd.kd, JOINT_NAMES)
        i = _SDK.index  # sdk[k] = description[i[k]]
        q, dq, kp, kd = q_des[i], dq_des[i], kp[i], kd[i]
        if use_stop_sentinels:
            q = np.where(kp == 0.0, POS_STOP_F, q)
            dq = np.where(kd == 0.0, VEL_STOP_F, dq)
        return cls(mode=np.full(SDK_LEG_MOTORS, MODE_ENABLE), q=q, dq=dq, tau=tau_ff[i],
                   kp=kp, kd=kd)

    def to_motor_command(self) -> MotorCommand:
        """The same command in the description order, as this library's drivers take it.

        Unused targets come back as zero: ``q_des = 0`` where ``q`` is :data:`POS_STOP_F`
        (``kp`` is 0 there), ``dq_des = 0`` where ``dq`` is :data:`VEL_STOP_F` (``kd`` is
        0 there). A stopped motor (``mode = 0x00``) applies no torque: it comes back as all
        zeros. Everything else is kept, so ``from_control_output`` then ``to_motor_command``
        returns the original command except for the targets a zero gain ignores.
        """
        enabled = self.mode == MODE_ENABLE
        q = np.where(enabled & ~_is_stop(self.q, POS_STOP_F), self.q, 0.0)
        dq = np.where(enabled & ~_is_stop(self.dq, VEL_STOP_F), self.dq, 0.0)
        sdk = MotorCommand(q_des=q, dq_des=dq, kp=np.where(enabled, self.kp, 0.0),
                           kd=np.where(enabled, self.kd, 0.0),
                           tau_ff=np.where(enabled, self.tau, 0.0))
        return sdk.reordered(_SDK.inverse)

    def torque_at(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The torque [N m] (12,) the drivers apply at the measured state, SDK order.

        ``tau + kp (q_cmd - q) + kd (dq_cmd - dq)`` at motor positions ``q`` [rad] and
        velocities ``dq`` [rad/s]; zero for a stopped motor. Unclipped.
        """
        q = as_vector("q (measured)", q, SDK_LEG_MOTORS)
        dq = as_vector("dq (measured)", dq, SDK_LEG_MOTORS)
        tau = self.tau + self.kp * (self.q - q) + self.kd * (self.dq - dq)
        return np.where(self.mode == MODE_ENABLE, tau, 0.0)

    def as_20_slots(self) -> dict[str, np.ndarray]:
        """The whole ``motor_cmd`` list: ``{"mode", "q", "dq", "tau", "kp", "kd"}`` -> (20,).

        Keys are the ``MotorCmd_`` attribute names; slots 0 to 11 are this command, slots 12
        to 19 (no GO2 motor) are stopped with zeros.
        """
        slots: dict[str, np.ndarray] = {}
        for name in _COMMAND_FIELDS:
            values = getattr(self, name)
            slots[name] = np.zeros(SDK_MOTOR_SLOTS, dtype=values.dtype)
            slots[name][:SDK_LEG_MOTORS] = values
        slots["mode"][SDK_LEG_MOTORS:] = MODE_STOP
        return slots

    def write_to(self, low_cmd: Any) -> None:
        """Set ``low_cmd.motor_cmd[0..19]`` (a ``LowCmd_`` or anything shaped like one).

        Only the motor entries are written: the header (``head``, ``level_flag``) and the
        ``crc``, which the SDK computes over the finished message, are the caller's.

        Raises:
            ConfigurationError: ``low_cmd`` has no ``motor_cmd`` list of 20 entries.
        """
        motors = getattr(low_cmd, "motor_cmd", None)
        if not hasattr(motors, "__len__") or len(motors) != SDK_MOTOR_SLOTS:
            raise ConfigurationError(
                f"low_cmd: expected a LowCmd_ with a motor_cmd list of {SDK_MOTOR_SLOTS} "
                f"entries, received {type(low_cmd).__name__}"
            )
        slots = self.as_20_slots()
        for k, motor in enumerate(motors):
            motor.mode = int(slots["mode"][k])
            for name in _COMMAND_FIELDS[1:]:
                setattr(motor, name, float(slots[name][k]))


@dataclass
class SdkLowState:
    """The part of ``LowState_`` the controller needs; motors and feet in SDK order.

    Arrays are copied on construction. See the module docstring for the fields, units and
    orders; :meth:`to_pinocchio` gives the controller's ``(q, v)``.

    Raises:
        ConfigurationError: A wrong shape, a non-finite value, or an IMU quaternion of
            (near) zero norm.
    """

    #: Base orientation, (w, x, y, z), scalar first.
    imu_quaternion_wxyz: np.ndarray
    #: Base angular velocity in the base frame [rad/s] (3,).
    gyroscope_rad_s: np.ndarray
    #: Specific force in the base frame [m/s^2] (3,).
    accelerometer_m_s2: np.ndarray
    #: Motor positions [rad] (12,), SDK order.
    q: np.ndarray
    #: Motor velocities [rad/s] (12,), SDK order.
    dq: np.ndarray
    #: Estimated motor torques [N m] (12,), SDK order.
    tau_est: np.ndarray
    #: Raw foot force readings (4,), legs FR, FL, RR, RL.
    foot_force: np.ndarray
    #: The robot's sample counter (``LowState_.tick``); 0 when not known.
    tick: int = 0

    def __post_init__(self) -> None:
        self.imu_quaternion_wxyz = as_vector("imu_quaternion_wxyz", self.imu_quaternion_wxyz, 4)
        _unit_quaternion("imu_quaternion_wxyz", self.imu_quaternion_wxyz, "w, x, y, z")
        self.gyroscope_rad_s = as_vector("gyroscope_rad_s", self.gyroscope_rad_s, 3)
        self.accelerometer_m_s2 = as_vector("accelerometer_m_s2", self.accelerometer_m_s2, 3)
        self.q = as_vector("q", self.q, SDK_LEG_MOTORS)
        self.dq = as_vector("dq", self.dq, SDK_LEG_MOTORS)
        self.tau_est = as_vector("tau_est", self.tau_est, SDK_LEG_MOTORS)
        self.foot_force = as_vector("foot_force", self.foot_force, len(UNITREE_SDK_LEGS))
        if isinstance(self.tick, bool) or not isinstance(self.tick, (int, np.integer)):
            raise ConfigurationError(
                f"tick: expected a whole number (LowState_.tick), received {self.tick!r}")
        self.tick = int(self.tick)

    @classmethod
    def from_message(cls, low_state: Any) -> SdkLowState:
        """Read a ``LowState_`` (or anything with its attributes): IMU, motors 0-11, feet.

        Raises:
            ConfigurationError: A missing attribute (named), or a field that fails the
                checks of the constructor.
        """
        try:
            imu = low_state.imu_state
            motors = [low_state.motor_state[k] for k in range(SDK_LEG_MOTORS)]
            return cls(
                imu_quaternion_wxyz=imu.quaternion, gyroscope_rad_s=imu.gyroscope,
                accelerometer_m_s2=imu.accelerometer, q=[m.q for m in motors],
                dq=[m.dq for m in motors], tau_est=[m.tau_est for m in motors],
                foot_force=low_state.foot_force, tick=int(getattr(low_state, "tick", 0)),
            )
        except (AttributeError, IndexError, TypeError) as err:
            raise _not_a_low_state(low_state, err) from err

    def to_pinocchio(self, base_position: np.ndarray | None = None,
                     base_linear_velocity_world: np.ndarray | None = None,
                     ) -> tuple[np.ndarray, np.ndarray]:
        """The controller's state: ``q`` (19,) and ``v`` (18,), description order.

        ``q = [base_position, quaternion (x, y, z, w), joints]`` with the IMU quaternion
        normalised; ``v = [linear velocity in the base frame, gyroscope, joint velocities]``.

        Args:
            base_position: Base position in the world [m] (3,), from a state estimator;
                zeros when not given.
            base_linear_velocity_world: Base linear velocity in the WORLD frame [m/s] (3,),
                from a state estimator (rotated into the base frame here); zeros when not
                given.

        Raises:
            ConfigurationError: A wrong shape or a non-finite value in an argument.
        """
        p = np.zeros(3) if base_position is None else as_vector("base_position",
                                                                 base_position, 3)
        vel = (np.zeros(3) if base_linear_velocity_world is None
               else as_vector("base_linear_velocity_world", base_linear_velocity_world, 3))
        quat = _unit_quaternion("imu_quaternion_wxyz", self.imu_quaternion_wxyz, "w, x, y, z")
        # SDK + estimator is MuJoCo's free-joint convention (w first, world linear velocity,
        # body angular velocity): reuse the library's one conversion.
        qpos = np.concatenate([p, quat, _SDK.from_other(self.q)])
        qvel = np.concatenate([vel, self.gyroscope_rad_s, _SDK.from_other(self.dq)])
        return mujoco_to_pin(qpos, qvel)

    def sensor_record(self, stamp_s: float | None = None) -> SensorRecord:
        """The same sample as a :class:`wbc.SensorRecord` in the description's orders
        (joints FL, FR, RL, RR x hip, thigh, calf; feet FL, FR, RL, RR), mapped by name:
        what :class:`wbc.StateEstimator` takes.

        Args:
            stamp_s: When it was taken [s]; by default ``tick`` read as milliseconds (the
                estimator falls back to its control period when stamps give no plausible
                step).
        """
        return _record(self.imu_quaternion_wxyz, self.gyroscope_rad_s, self.accelerometer_m_s2,
                       self.q, self.dq, self.tau_est, self.foot_force, self.tick, stamp_s)

    def to_message(self) -> SimpleNamespace:
        """This sample shaped as a ``LowState_``: ``imu_state.quaternion``, ``.gyroscope``,
        ``.accelerometer``; ``motor_state[0..19].q``, ``.dq``, ``.tau_est`` (slots 12-19
        zero); ``foot_force``; ``tick``. A stand-in for a robot's message wherever code
        reads one (:meth:`from_message`, :func:`sensor_record_from_message`): tests,
        examples, a simulator speaking as the robot does.
        """
        motors = [SimpleNamespace(q=0.0, dq=0.0, tau_est=0.0) for _ in range(SDK_MOTOR_SLOTS)]
        for k in range(SDK_LEG_MOTORS):
            motors[k] = SimpleNamespace(q=float(self.q[k]), dq=float(self.dq[k]),
                                        tau_est=float(self.tau_est[k]))
        imu = SimpleNamespace(quaternion=self.imu_quaternion_wxyz.tolist(),
                              gyroscope=self.gyroscope_rad_s.tolist(),
                              accelerometer=self.accelerometer_m_s2.tolist())
        return SimpleNamespace(imu_state=imu, motor_state=motors,
                               foot_force=self.foot_force.tolist(), tick=self.tick)

    def foot_forces_by_leg(self) -> dict[str, float]:
        """The raw foot force readings by leg, in the description's leg order (FL, FR, RL, RR)."""
        return {leg: float(self.foot_force[UNITREE_SDK_LEGS.index(leg)]) for leg in LEGS}

    def joint_torques(self) -> np.ndarray:
        """``tau_est`` [N m] in the description order (12,)."""
        return _SDK.from_other(self.tau_est)

    @classmethod
    def from_pinocchio(cls, q: np.ndarray, v: np.ndarray, *,
                       tau_est: np.ndarray | None = None,
                       foot_force_by_leg: Mapping[str, float] | None = None,
                       accelerometer_m_s2: np.ndarray | None = None) -> SdkLowState:
        """The record a robot in state ``(q, v)`` would send (simulation, round trips).

        The base position and the linear velocity are not in the record
        (:meth:`to_pinocchio` takes them back from an estimator).

        Args:
            q: Configuration (19,), Pinocchio convention, description order.
            v: Velocity (18,), Pinocchio convention, description order.
            tau_est: Joint torques [N m] (12,), description order; zeros when not given.
            foot_force_by_leg: Raw foot force reading of each leg ``FL, FR, RL, RR``;
                zeros when not given.
            accelerometer_m_s2: Specific force in the base frame (3,); when not given,
                that of a base at rest: gravity (:data:`GRAVITY_M_S2`) pointing up,
                in the base frame.

        Raises:
            ConfigurationError: A wrong shape, a non-finite value, a zero quaternion in
                ``q[3:7]``, or a missing leg in ``foot_force_by_leg``.
            UnknownNameError: A leg name that is not one of ``FL, FR, RL, RR``.
        """
        q = as_vector("q", q, NQ)
        v = as_vector("v", v, NV)
        q[3:7] = _unit_quaternion("q[3:7]", q[3:7], "x, y, z, w")
        qpos, qvel = pin_to_mujoco(q, v)
        tau = np.zeros(SDK_LEG_MOTORS) if tau_est is None else as_vector("tau_est", tau_est,
                                                                         SDK_LEG_MOTORS)
        feet = np.zeros(len(LEGS))
        if foot_force_by_leg is not None:
            for leg in foot_force_by_leg:
                check_name("leg", leg, LEGS)
            missing = [leg for leg in LEGS if leg not in foot_force_by_leg]
            if missing:
                raise ConfigurationError(
                    f"foot_force_by_leg: missing legs {missing}; expected one value for "
                    f"each of {', '.join(LEGS)}"
                )
            feet = as_vector("foot_force_by_leg", [foot_force_by_leg[leg] for leg in LEGS],
                             len(LEGS))
        if accelerometer_m_s2 is None:
            # Rotate the world's "up" specific force into the base frame with the same
            # conversion (it maps world-frame linear vectors to the base frame).
            up = np.zeros(NV)
            up[2] = GRAVITY_M_S2
            accelerometer_m_s2 = mujoco_to_pin(qpos, up)[1][:3]
        return cls(
            imu_quaternion_wxyz=qpos[3:7], gyroscope_rad_s=qvel[3:6],
            accelerometer_m_s2=accelerometer_m_s2, q=_SDK.to_other(q[7:]),
            dq=_SDK.to_other(v[6:]), tau_est=_SDK.to_other(tau),
            foot_force=[feet[LEGS.index(leg)] for leg in UNITREE_SDK_LEGS],
        )


#: Each description leg's slot in the SDK's foot order.
_SDK_LEG_SLOTS = np.array([UNITREE_SDK_LEGS.index(leg) for leg in LEGS])


def _record(quaternion: Any, gyroscope: Any, accelerometer: Any, q: Any, dq: Any, tau: Any,
            feet: Any, tick: int, stamp_s: float | None) -> SensorRecord:
    joints = _SDK.inverse
    return SensorRecord(
        stamp_s=tick * 1e-3 if stamp_s is None else stamp_s, tick=tick,
        imu_quaternion_wxyz=quaternion, gyroscope_rad_s=gyroscope,
        accelerometer_m_s2=accelerometer, q=np.asarray(q, dtype=float)[joints],
        dq=np.asarray(dq, dtype=float)[joints], tau_est=np.asarray(tau, dtype=float)[joints],
        foot_force=np.asarray(feet, dtype=float)[_SDK_LEG_SLOTS])


def sensor_record_from_message(low_state: Any, *, stamp_s: float | None = None) -> SensorRecord:
    """A ``LowState_`` (or anything with its attributes) as a :class:`wbc.SensorRecord` in
    the description's orders, for the state estimator.

    Unlike :meth:`SdkLowState.from_message`, non-finite readings pass through: a failing
    sensor is the estimator's to detect, report and work around, not a reason to stop the
    control loop. Missing attributes and wrong sizes still raise.

    Args:
        low_state: The message.
        stamp_s: When it was received [s]; by default its ``tick`` read as milliseconds.

    Raises:
        ConfigurationError: A missing attribute or a field of the wrong size (named).
    """
    try:
        imu = low_state.imu_state
        motors = [low_state.motor_state[k] for k in range(SDK_LEG_MOTORS)]
        return _record(imu.quaternion, imu.gyroscope, imu.accelerometer,
                       [m.q for m in motors], [m.dq for m in motors],
                       [m.tau_est for m in motors], low_state.foot_force,
                       int(getattr(low_state, "tick", 0)), stamp_s)
    except (AttributeError, IndexError, TypeError) as err:
        raise _not_a_low_state(low_state, err) from err


def _not_a_low_state(low_state: Any, err: Exception) -> ConfigurationError:
    return ConfigurationError(
        f"low_state: expected a LowState_ (imu_state.quaternion, .gyroscope, .accelerometer; "
        f"motor_state[0..{SDK_LEG_MOTORS - 1}].q, .dq, .tau_est; foot_force), received "
        f"{type(low_state).__name__}: {err}")
