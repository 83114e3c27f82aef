"""The robot as behaviours see it: sensors in, motor commands out, joints wired by name.

Sim-to-real: a behaviour never talks to MuJoCo or to a motor driver. It talks to a
:class:`RobotInterface` in the robot's own joint order (a MuJoCo plant, the Unitree SDK's
FR, FL, RR, RL order, ...), wrapped in a :class:`MappedRobot` that converts, by joint and
leg name, to the description order the controller and the estimator use. Swapping the
simulator for the real robot changes the interface object and its names, not the behaviour
code.

A robot reports what it measures, a :class:`wbc.SensorRecord` per control period (IMU,
joint encoders and torques, foot-force counts), never its base position or velocity, which
a real GO2 does not measure: the control loop's state estimator turns the records into the
controller's ``(q, v)``. A simulated robot also knows its true state (:class:`TrueState`),
which metrics, logs and tests read, and which ``--state truth`` hands the controller.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import JOINT_NAMES, LEGS
from wbc.model.joint_map import JointMap
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord

#: Where a control loop's state comes from: estimated from the robot's sensors (the default,
#: as on a real GO2), or the exact state of a simulated robot.
STATE_SOURCES = ("estimate", "truth")


@runtime_checkable
class RobotInterface(Protocol):
    """A robot in its own joint and leg orders."""

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The robot's joints, in the order its arrays use."""

    @property
    def leg_names(self) -> tuple[str, ...]:
        """The robot's legs, in the order of its foot-force array."""

    @property
    def time_s(self) -> float:
        """The robot's clock [s] (simulated time for a simulator)."""

    def read_sensors(self) -> SensorRecord | None:
        """This period's sensor sample in the robot's orders, or ``None`` if none came.

        The record may be the robot's own buffer, refilled by the next call.
        """

    def write_command(self, command: MotorCommand) -> None:
        """Hand the motor drivers one command (arrays (12,) in the robot's order).

        The drivers apply ``tau_ff + kp (q_des - q) + kd (dq_des - dq)`` until the next
        command, one control period later. A plant that takes bare torques applies
        :meth:`~wbc.robot_io.motor_command.MotorCommand.torque_at` the state it measured.
        """


@runtime_checkable
class TrueState(Protocol):
    """A robot that knows its exact floating-base state: a simulator, not a real GO2."""

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q (19,), v (18,))``: Pinocchio-convention base, joints in the robot's order."""


class RobotWrapper:
    """A robot that passes everything on to the robot it wraps, in the same orders: the base
    of robots that change one thing (a command delay, sensor faults)."""

    def __init__(self, robot: RobotInterface):
        self.robot = robot

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The robot's joint order."""
        return self.robot.joint_names

    @property
    def leg_names(self) -> tuple[str, ...]:
        """The robot's leg order."""
        return self.robot.leg_names

    @property
    def time_s(self) -> float:
        """The robot's clock [s]."""
        return self.robot.time_s

    def read_sensors(self) -> SensorRecord | None:
        """The robot's sensor record."""
        return self.robot.read_sensors()

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's exact state (simulators only)."""
        return self.robot.read_state()  # type: ignore[attr-defined]

    def write_command(self, command: MotorCommand) -> None:
        """Passed on."""
        self.robot.write_command(command)


class MappedRobot:
    """A :class:`RobotInterface` seen in the description's joint and leg orders.

    Args:
        robot: The robot, in its own orders.
        aliases: Its joint names mapped to the description's, where they differ.
    """

    def __init__(self, robot: RobotInterface, *, aliases: dict[str, str] | None = None):
        self.robot = robot
        self.joint_map = JointMap(robot.joint_names, aliases=aliases)
        #: The robot's order is the description's: arrays are copied, not reordered.
        self._same_order = bool(np.array_equal(self.joint_map.index, np.arange(len(JOINT_NAMES))))
        legs = tuple(getattr(robot, "leg_names", LEGS))
        for leg in legs:
            check_name("leg", leg, LEGS)
        if sorted(legs) != sorted(LEGS):
            raise ConfigurationError(
                f"leg_names: expected each of {', '.join(LEGS)} once, received {list(legs)}")
        #: ``robot foot_force[i]`` is the description's leg ``leg_index[i]``.
        self._leg_inverse = np.argsort(np.array([LEGS.index(leg) for leg in legs]))
        self._same_legs = legs == LEGS
        self._record = SensorRecord.zeros()

    @property
    def time_s(self) -> float:
        """The robot's clock [s]."""
        return self.robot.time_s

    @property
    def has_true_state(self) -> bool:
        """The robot knows its exact state (a simulator)."""
        return isinstance(self.robot, TrueState)

    def read_sensors(self) -> SensorRecord | None:
        """This period's sample in the description's orders (``None`` if none came).

        The record is this object's buffer (or, in the description's orders already, the
        robot's), refilled by the next call.

        Raises:
            ConfigurationError: The robot returned something that is not a record.
        """
        record = self.robot.read_sensors()
        if record is None:
            return None
        if not isinstance(record, SensorRecord):
            raise ConfigurationError(
                f"read_sensors: expected a SensorRecord or None, received "
                f"{type(record).__name__}")
        if self._same_order and self._same_legs:
            return record
        mapped = self._record
        mapped.stamp_s, mapped.tick = record.stamp_s, record.tick
        mapped.imu_quaternion_wxyz[:] = record.imu_quaternion_wxyz
        mapped.gyroscope_rad_s[:] = record.gyroscope_rad_s
        mapped.accelerometer_m_s2[:] = record.accelerometer_m_s2
        inverse = self.joint_map.inverse
        np.take(record.q, inverse, out=mapped.q)
        np.take(record.dq, inverse, out=mapped.dq)
        np.take(record.tau_est, inverse, out=mapped.tau_est)
        np.take(record.foot_force, self._leg_inverse, out=mapped.foot_force)
        return mapped

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The exact ``(q, v)`` with the joints in the description order (simulators only).

        Raises:
            ConfigurationError: The robot does not know its exact state (a real robot).
        """
        if not self.has_true_state:
            raise ConfigurationError(
                f"state: {type(self.robot).__name__} reports sensors only, not its exact "
                "state; estimate it (the default) instead of 'truth'")
        q, v = self.robot.read_state()
        q = as_vector("q", q, 19, finite=False)
        v = as_vector("v", v, 18, finite=False)
        if not self._same_order:
            q[7:] = q[7:][self.joint_map.inverse]
            v[6:] = v[6:][self.joint_map.inverse]
        return q, v

    def write_command(self, command: MotorCommand) -> None:
        """A motor command in the description order, sent in the robot's order (a copy)."""
        if self._same_order:
            self.robot.write_command(command.copy())
        else:
            self.robot.write_command(command.reordered(self.joint_map.index))
