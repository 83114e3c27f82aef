"""The part of the Unitree SDK's ``rt/lowstate`` (``LowState_``) the controller and the state
estimator read, and the message as a :class:`wbc.SensorRecord`.

The fields, units and the SDK's orders are in :mod:`wbc.robot_io.unitree_sdk`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np

from wbc.core.conventions import GRAVITY_M_S2, NQ, NV, mujoco_to_pin, pin_to_mujoco
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, as_whole_number, check_name
from wbc.model.description import LEGS, UNITREE_SDK_LEGS
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS, Orders
from wbc.robot_io.sensor_record import SensorRecord
from wbc.robot_io.unitree_sdk import SDK_LEG_MOTORS, SDK_MOTOR_SLOTS

_SDK = JointMap.unitree_sdk()
_MIN_QUATERNION_NORM = 1e-6


def _unit_quaternion(name: str, quat: np.ndarray, order: str) -> np.ndarray:
    norm = float(np.linalg.norm(quat))
    if norm < _MIN_QUATERNION_NORM:
        raise ConfigurationError(
            f"{name}: expected a unit quaternion ({order}), received {quat.tolist()} "
            f"(norm {norm:g}; a norm of at least {_MIN_QUATERNION_NORM:g} is normalised)"
        )
    return quat / norm


@dataclass
class SdkLowState:
    """The part of ``LowState_`` the controller needs; motors and feet in SDK order.

    Arrays are copied on construction. See :mod:`wbc.robot_io.unitree_sdk` for the fields,
    units and orders; :meth:`to_pinocchio` gives the controller's ``(q, v)``.

    Raises:
        ConfigurationError: A wrong shape, a non-finite value, or an IMU quaternion of
            (near) zero norm.
    """

    #: Always the Unitree SDK's (motors and feet FR, FL, RR, RL).
    orders: ClassVar[Orders] = UNITREE_SDK_ORDERS
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
        self.tick = as_whole_number("tick", self.tick, "LowState_.tick")

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
                accelerometer_m_s2=imu.accelerometer, q=np.array([m.q for m in motors]),
                dq=np.array([m.dq for m in motors]),
                tau_est=np.array([m.tau_est for m in motors]),
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
        what :class:`wbc.StateEstimator` takes. Its ``orders`` say so: a robot returning
        it from ``read_sensors()`` declares the description's orders (``JOINT_NAMES``,
        ``LEGS``), not the SDK's.

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
                that of a base at rest: gravity
                (:data:`wbc.core.conventions.GRAVITY_M_S2`) pointing up, in the base frame.

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
            foot_force=np.array([feet[LEGS.index(leg)] for leg in UNITREE_SDK_LEGS]),
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
        foot_force=np.asarray(feet, dtype=float)[_SDK_LEG_SLOTS], orders=DESCRIPTION_ORDERS)


def sensor_record_from_message(low_state: Any, *, stamp_s: float | None = None) -> SensorRecord:
    """A ``LowState_`` (or anything with its attributes) as a :class:`wbc.SensorRecord` in
    the description's orders, for the state estimator.

    The message is in the SDK's orders (FR, FL, RR, RL); the record is not: it is mapped by
    name and tagged :data:`~wbc.model.orders.DESCRIPTION_ORDERS`. A
    :class:`~actions.robot.robot_interface.RobotInterface` that returns it from
    ``read_sensors()`` declares the description's orders (``joint_names = JOINT_NAMES``,
    ``leg_names = LEGS``); one that declares the SDK's is refused by the loop, naming both.

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
