"""The robot as behaviours see it: sensors in, motor commands out, joints wired by name.

Sim-to-real: a behaviour never talks to MuJoCo or to a motor driver. It talks to a
:class:`RobotInterface` in the robot's own joint order (a MuJoCo plant, the Unitree SDK's
FR, FL, RR, RL order, ...), wrapped in a :class:`MappedRobot` that converts, by joint and
leg name, to the description order the controller and the estimator use. Swapping the
simulator for the real robot changes the interface object and its names, not the behaviour
code.

Each record and command carries its orders (:class:`wbc.model.orders.Orders`): a robot
declares its ``joint_names`` and ``leg_names``, fills its records in those orders
(``SensorRecord.zeros(Orders.of(joint_names, leg_names))``), and :class:`MappedRobot`
refuses a record or command in any other, naming both (a record already mapped to the
description's, from :func:`wbc.sensor_record_from_message`, returned by a robot that declares
the Unitree SDK's orders, would otherwise have its feet swapped). :func:`check_robot`, run
when a control loop starts, lists what a robot lacks.

A robot reports what it measures, a :class:`wbc.SensorRecord` per control period (IMU,
joint encoders and torques, foot-force counts), never its base position or velocity, which
a real GO2 does not measure: the control loop's state estimator turns the records into the
controller's ``(q, v)``. A simulated robot also knows its true state (:class:`TrueState`),
which metrics, logs and tests read, and which ``--state truth`` hands the controller.
What else a robot may offer (wait for its next state, count the states it skipped, ...) it
declares by the protocols of :mod:`actions.robot.robot_capabilities`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, cast, runtime_checkable

import numpy as np

from actions.robot.robot_capabilities import AppliesCommandAtOnce
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS, Orders
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord

#: Where a control loop's state comes from: estimated from the robot's sensors (the default,
#: as on a real GO2), or the exact state of a simulated robot.
STATE_SOURCES = ("estimate", "truth")


@runtime_checkable
class RobotInterface(Protocol):
    """A robot in its own joint and leg orders: five members, ``joint_names``,
    ``leg_names``, ``time_s``, ``read_sensors()`` and ``write_command()``.

    Its records carry the orders it declares (``SensorRecord.zeros(Orders.of(joint_names,
    leg_names))``), its commands arrive in them. A robot without sensors that knows its
    exact state (:class:`TrueState`) runs with ``state="truth"`` instead of
    ``read_sensors()``.
    """

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

        The record may be the robot's own buffer, refilled by the next call. Its
        ``orders`` are the robot's declared ones (checked).
        """

    def write_command(self, command: MotorCommand) -> None:
        """Hand the motor drivers one command (arrays (12,) in the robot's order, which
        ``command.orders`` names).

        The drivers apply ``tau_ff + kp (q_des - q) + kd (dq_des - dq)`` until the next
        command, one control period later. A plant that takes bare torques applies
        :meth:`~wbc.robot_io.motor_command.MotorCommand.torque_at` the state it measured.
        """


@runtime_checkable
class TrueState(Protocol):
    """A robot that knows its exact floating-base state: a simulator, not a real GO2."""

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q (19,), v (18,))``: Pinocchio-convention base, joints in the robot's order."""


#: The :class:`RobotInterface`'s members, methods with their parentheses.
ROBOT_MEMBERS = ("joint_names", "leg_names", "time_s", "read_sensors()", "write_command()")
#: What a robot declares so that its arrays are mapped by name, ending a refusal.
DECLARE_ORDERS = (
    "declare joint_names and leg_names, the orders of its joint and foot-force arrays "
    "(wbc.JOINT_NAMES and wbc.LEGS for the description's, wbc.UNITREE_SDK_JOINT_NAMES and "
    "wbc.UNITREE_SDK_LEGS for the Unitree SDK's)")


def check_robot(robot: object, *, state: str = "estimate") -> None:
    """Refuse, in one line, a robot that lacks a member the control loop uses.

    With ``state="estimate"`` (the default) those are :data:`ROBOT_MEMBERS`; with
    ``"truth"``, ``read_state()`` (:class:`TrueState`) instead of ``read_sensors()``. The
    message lists every missing member, points a robot without sensors that knows its exact
    state to ``state="truth"``, and says what to declare for the orders.

    Raises:
        ConfigurationError: ``"robot: OldGo2 lacks read_sensors() of the RobotInterface
            (joint_names, leg_names, time_s, read_sensors(), write_command()); ..."``.
    """
    truth = state == "truth"
    members = tuple(("read_state()" if m == "read_sensors()" else m) if truth else m
                    for m in ROBOT_MEMBERS)

    def lacks(member: str) -> bool:
        name = member.removesuffix("()")
        if not hasattr(robot, name):
            return True
        return member.endswith("()") and not callable(getattr(robot, name))

    missing = [m for m in members if lacks(m)]
    if not missing:
        return
    kind = "RobotInterface and TrueState" if truth else "RobotInterface"
    notes = [(f"robot: {type(robot).__name__} lacks {', '.join(missing)} of the {kind} "
              f"({', '.join(members)})")]
    if "read_sensors()" in missing:
        notes.append("it has read_state(): a robot without sensors runs on its exact state "
                     "with state='truth'" if not lacks("read_state()") else
                     "a robot without sensors that knows its exact state (read_state()) "
                     "runs with state='truth'")
    if "read_state()" in missing:
        notes.append("it reports sensors only, not its exact state (which only a simulator "
                     "knows): estimate it with state='estimate' (the default) instead of "
                     "'truth'")
    if "joint_names" in missing or "leg_names" in missing:
        notes.append(DECLARE_ORDERS)
    raise ConfigurationError("; ".join(notes))


def declared_orders(robot: object) -> Orders:
    """The orders ``robot`` declares (``joint_names``, ``leg_names``), interned.

    Raises:
        ConfigurationError: It declares none (one line saying what to declare), or names
            that are not 12 distinct joints and the four legs once each.
    """
    if not (hasattr(robot, "joint_names") and hasattr(robot, "leg_names")):
        raise ConfigurationError(
            f"robot: {type(robot).__name__} does not declare its orders: {DECLARE_ORDERS}")
    try:
        return Orders.of(tuple(robot.joint_names), tuple(robot.leg_names),
                         name=f"{type(robot).__name__}'s")
    except (ConfigurationError, TypeError) as err:
        raise ConfigurationError(f"robot: {type(robot).__name__}.{err}") from err


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

    Checks the orders both ways: a record the robot returns must be in its declared orders
    (:attr:`robot_orders`), a command it is given in the description's; either mismatch
    raises :class:`~wbc.core.errors.OrderMismatchError` naming both.

    Args:
        robot: The robot, in its own orders.
        aliases: Its joint names mapped to the description's, where they differ.

    Raises:
        ConfigurationError: A robot that does not declare its orders, or declares names
            that are not the GO2's joints and legs.
    """

    def __init__(self, robot: RobotInterface, *, aliases: dict[str, str] | None = None):
        self.robot = robot
        #: The orders the robot declares, which its records carry.
        self.robot_orders = declared_orders(robot)
        self.joint_map = JointMap(self.robot_orders.joint_names, aliases=aliases)
        #: The robot's arrays are the description's, names included: passed, not mapped.
        self._same_order = self.robot_orders is DESCRIPTION_ORDERS
        legs = self.robot_orders.leg_names
        #: ``description foot_force[j] = robot foot_force[_leg_inverse[j]]``.
        self._leg_inverse = np.argsort(np.array([DESCRIPTION_ORDERS.leg_names.index(leg)
                                                 for leg in legs]))
        self._record = SensorRecord.zeros()
        self._true_state_of: object = None  # the robot has_true_state last judged
        self._apply_of: object = None  # the robot _apply was judged for
        self._apply: Callable[[MotorCommand], None] | None = None
        self._true_state = False

    @property
    def time_s(self) -> float:
        """The robot's clock [s]."""
        return self.robot.time_s

    @property
    def has_true_state(self) -> bool:
        """The robot knows its exact state (a simulator)."""
        robot = self.robot
        if self._true_state_of is not robot:  # once per robot: a protocol's isinstance costs
            self._true_state_of = robot       # microseconds, and the tick asks every time
            self._true_state = isinstance(robot, TrueState)
        return self._true_state

    def read_sensors(self) -> SensorRecord | None:
        """This period's sample in the description's orders (``None`` if none came).

        The record is this object's buffer (or, in the description's orders already, the
        robot's), refilled by the next call.

        Raises:
            ConfigurationError: The robot returned something that is not a record.
            OrderMismatchError: A record in other orders than the robot declares.
        """
        record = self.robot.read_sensors()
        if record is None:
            return None
        if not isinstance(record, SensorRecord):
            raise ConfigurationError(
                f"read_sensors: expected a SensorRecord or None, received "
                f"{type(record).__name__}")
        if record.orders is not self.robot_orders:
            record.orders.check(
                self.robot_orders, what=f"{type(self.robot).__name__}.read_sensors()",
                fix="return records in the orders it declares (fill "
                    "SensorRecord.zeros(Orders.of(joint_names, leg_names))), or declare "
                    "the orders its records are in")
        if self._same_order:
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
        q, v = cast(TrueState, self.robot).read_state()  # has_true_state: it is one
        q = as_vector("q", q, 19, finite=False)
        v = as_vector("v", v, 18, finite=False)
        if not self._same_order:
            q[7:] = q[7:][self.joint_map.inverse]
            v[6:] = v[6:][self.joint_map.inverse]
        return q, v

    def write_command(self, command: MotorCommand) -> None:
        """A motor command in the description order, sent in the robot's order (a copy;
        ``command`` itself to a robot in the description's order that applies it at once,
        :class:`~actions.robot.robot_capabilities.AppliesCommandAtOnce`).

        Raises:
            OrderMismatchError: ``command`` is in another joint order (already the robot's).
        """
        if command.orders is not DESCRIPTION_ORDERS:
            command.orders.check(
                DESCRIPTION_ORDERS, what="write_command(command)", legs=False,
                fix="pass the controller's command as it is (the description's order): "
                    "this robot maps it to its own by name")
        robot = self.robot
        if robot is not self._apply_of:  # once per robot: a protocol's isinstance costs
            self._apply_of = robot       # microseconds, and the tick writes every time
            self._apply = (robot.apply_command if isinstance(robot, AppliesCommandAtOnce)
                           else None)
        if self._same_order:
            if self._apply is not None:  # applied before it returns: no copy to keep
                self._apply(command)
            else:
                robot.write_command(command.copy())
        else:
            self.robot.write_command(command.reordered(self.joint_map.index,
                                                       orders=self.robot_orders))
