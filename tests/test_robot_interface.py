"""The robot interface: the loop-start check, the orders MappedRobot checks, the exports."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import actions
import actions.robot
from actions.robot import control_loop, robot_interface
from actions.robot.robot_interface import MappedRobot, check_robot
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError, OrderMismatchError
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS, Orders
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_low_state import SdkLowState, sensor_record_from_message
from wbc.robot_io.sensor_record import SensorRecord

ROOT = Path(__file__).resolve().parents[1]
MEMBERS = "(joint_names, leg_names, time_s, read_sensors(), write_command())"
DECLARE = ("declare joint_names and leg_names, the orders of its joint and foot-force arrays "
           "(wbc.JOINT_NAMES and wbc.LEGS for the description's, wbc.UNITREE_SDK_JOINT_NAMES "
           "and wbc.UNITREE_SDK_LEGS for the Unitree SDK's)")
SDK = "the Unitree SDK's orders (joints and feet by leg FR, FL, RR, RL)"
DESCRIPTION = "the description's orders (joints and feet by leg FL, FR, RL, RR)"


class SdkGo2:
    """A robot in the Unitree SDK's orders, whose record is whatever the test hands it."""

    joint_names = UNITREE_SDK_JOINT_NAMES
    leg_names = UNITREE_SDK_LEGS
    time_s = 0.0

    def __init__(self, record: SensorRecord) -> None:
        self.record = record
        self.commands: list[MotorCommand] = []

    def read_sensors(self) -> SensorRecord:
        return self.record

    def write_command(self, command: MotorCommand) -> None:
        self.commands.append(command)


class OldGo2:
    """A robot written to the previous interface: its exact state, no sensors, no legs."""

    joint_names = JOINT_NAMES
    time_s = 0.0

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros(19), np.zeros(18)

    def write_command(self, command: MotorCommand) -> None:
        pass


class NoOrders:
    """Every member but the orders."""

    time_s = 0.0

    def read_sensors(self) -> SensorRecord:
        return SensorRecord.zeros()

    def write_command(self, command: MotorCommand) -> None:
        pass


def sdk_record() -> SensorRecord:
    """A record in the SDK's orders: joint k holds k, foot k holds 10 k."""
    record = SensorRecord.zeros(UNITREE_SDK_ORDERS)
    record.q[:] = np.arange(12.0)
    record.foot_force[:] = [0.0, 10.0, 20.0, 30.0]
    return record


@pytest.fixture(scope="module")
def controller() -> WholeBodyController:
    return WholeBodyController()


# ------------------------------------------------------------------ the loop-start check


def test_a_robot_written_to_the_previous_interface_gets_every_missing_member(controller):
    with pytest.raises(ConfigurationError) as error:
        control_loop.ControlLoop(OldGo2(), controller)
    assert str(error.value) == (
        f"robot: OldGo2 lacks leg_names, read_sensors() of the RobotInterface {MEMBERS}; it "
        "has read_state(): a robot without sensors runs on its exact state with "
        f"state='truth'; {DECLARE}")


def test_a_robot_without_declared_orders_is_refused_in_one_line(controller):
    with pytest.raises(ConfigurationError) as error:
        control_loop.ControlLoop(NoOrders(), controller)
    assert str(error.value) == (
        f"robot: NoOrders lacks joint_names, leg_names of the RobotInterface {MEMBERS}; "
        f"{DECLARE}")
    with pytest.raises(ConfigurationError) as direct:  # the mapping alone says the same
        MappedRobot(NoOrders())  # type: ignore[arg-type]
    assert str(direct.value) == f"robot: NoOrders does not declare its orders: {DECLARE}"
    assert "\n" not in str(error.value) + str(direct.value)


def test_the_check_names_what_truth_needs_and_methods_that_are_not_callable():
    robot = SdkGo2(sdk_record())
    check_robot(robot)  # complete: no error
    with pytest.raises(ConfigurationError) as error:
        check_robot(robot, state="truth")
    assert str(error.value) == (
        "robot: SdkGo2 lacks read_state() of the RobotInterface and TrueState (joint_names, "
        "leg_names, time_s, read_state(), write_command()); it reports sensors only, not its "
        "exact state (which only a simulator knows): estimate it with state='estimate' (the "
        "default) instead of 'truth'")
    with pytest.raises(ConfigurationError) as old:  # what truth needs, but the leg order
        check_robot(OldGo2(), state="truth")
    assert str(old.value) == (
        "robot: OldGo2 lacks leg_names of the RobotInterface and TrueState (joint_names, "
        f"leg_names, time_s, read_state(), write_command()); {DECLARE}")
    robot.write_command = "not a method"  # type: ignore[assignment]
    with pytest.raises(ConfigurationError, match=r"^robot: SdkGo2 lacks write_command\(\) of "):
        check_robot(robot)


def test_declared_names_that_are_not_the_go2s_are_named():
    robot = SdkGo2(sdk_record())
    robot.leg_names = ("FL", "FR", "RL", "XX")  # type: ignore[misc]
    with pytest.raises(ConfigurationError) as error:
        MappedRobot(robot)
    assert str(error.value) == ("robot: SdkGo2.leg_names: expected each of FL, FR, RL, RR "
                                "once, received ['FL', 'FR', 'RL', 'XX']")


# -------------------------------------------------------- the orders, checked both ways


def test_a_record_in_the_descriptions_orders_from_a_robot_that_declares_the_sdks_is_refused():
    state = SdkLowState.from_pinocchio(np.r_[0, 0, 0.3, 0, 0, 0, 1, np.zeros(12)],
                                       np.zeros(18))
    mapped = MappedRobot(SdkGo2(sensor_record_from_message(state.to_message())))
    with pytest.raises(OrderMismatchError) as error:
        mapped.read_sensors()
    assert str(error.value) == (
        f"SdkGo2.read_sensors(): in {DESCRIPTION}, expected {SDK}: return records in the "
        "orders it declares (fill SensorRecord.zeros(Orders.of(joint_names, leg_names))), or "
        "declare the orders its records are in")


def test_a_record_in_the_robots_orders_is_mapped_by_name():
    mapped = MappedRobot(SdkGo2(sdk_record()))
    record = mapped.read_sensors()
    assert record.orders is DESCRIPTION_ORDERS
    assert record.q[JOINT_NAMES.index("FR_hip_joint")] == 0.0  # SDK slot 0
    assert record.q[JOINT_NAMES.index("FL_hip_joint")] == 3.0  # SDK slot 3
    np.testing.assert_array_equal(record.foot_force, [10.0, 0.0, 30.0, 20.0])  # FL FR RL RR


def test_a_command_already_in_the_robots_order_is_refused():
    robot = SdkGo2(sdk_record())
    mapped = MappedRobot(robot)
    command = MotorCommand.pure_torque(np.arange(12.0))
    mapped.write_command(command)
    sent = robot.commands[-1]
    assert sent.orders is UNITREE_SDK_ORDERS
    assert sent.tau_ff[0] == JOINT_NAMES.index("FR_hip_joint")
    with pytest.raises(OrderMismatchError) as error:
        mapped.write_command(sent)  # mapped once already
    assert str(error.value) == (
        "write_command(command): in the Unitree SDK's joint order (by leg FR, FL, RR, RL), "
        "expected the description's joint order (by leg FL, FR, RL, RR): pass the "
        "controller's command as it is (the description's order): this robot maps it to its "
        "own by name")
    assert len(robot.commands) == 1


def test_a_robot_with_aliases_in_the_descriptions_order_is_mapped_and_checked():
    aliases = {name.removesuffix("_joint"): name for name in JOINT_NAMES}
    orders = Orders.of(tuple(aliases), LEGS)
    robot = SdkGo2(SensorRecord.zeros(orders))
    robot.joint_names, robot.leg_names = tuple(aliases), LEGS  # type: ignore[misc]
    robot.record.q[:] = np.arange(12.0)
    mapped = MappedRobot(robot, aliases=aliases)
    record = mapped.read_sensors()
    assert record.orders is DESCRIPTION_ORDERS and record is not robot.record
    np.testing.assert_array_equal(record.q, np.arange(12.0))
    mapped.write_command(MotorCommand.pure_torque(np.zeros(12)))
    assert robot.commands[-1].orders is orders


def test_a_robot_in_the_descriptions_orders_passes_its_record_through():
    robot = SdkGo2(SensorRecord.zeros())
    robot.joint_names, robot.leg_names = JOINT_NAMES, LEGS  # type: ignore[misc]
    mapped = MappedRobot(robot)
    assert mapped.robot_orders is DESCRIPTION_ORDERS
    assert mapped.read_sensors() is robot.record
    sdk = MotorCommand.pure_torque(np.zeros(12)).reordered(JointMap.unitree_sdk().index)
    with pytest.raises(OrderMismatchError, match=r"^write_command\(command\): in the Unitree"):
        mapped.write_command(sdk)


# ------------------------------------------------------------------------- the exports


def test_the_robot_loop_is_exported_where_a_user_looks_for_it():
    from actions import ControlLoop, MappedRobot, RobotInterface, TrueState
    from actions.robot import ControlLoop as LoopFromRobot

    assert ControlLoop is LoopFromRobot is control_loop.ControlLoop
    assert RobotInterface is robot_interface.RobotInterface
    assert TrueState is robot_interface.TrueState and MappedRobot is robot_interface.MappedRobot
    assert actions.check_robot is actions.robot.check_robot is check_robot
    for name in ("ControlLoop", "MappedRobot", "RobotInterface", "TrueState", "check_robot"):
        assert name in actions.__all__ and name in actions.robot.__all__ and name in dir(actions)
    assert isinstance(SdkGo2(sdk_record()), RobotInterface)
    with pytest.raises(AttributeError, match="^module 'actions' has no attribute 'Robot'$"):
        actions.Robot  # noqa: B018


def test_importing_actions_leaves_the_robot_loop_until_it_is_used():
    code = ("import sys, actions; loaded = 'actions.robot.control_loop' in sys.modules; "
            "actions.ControlLoop; sys.exit(10 * loaded + "
            "('actions.robot.control_loop' not in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=ROOT, check=False)
    assert done.returncode == 0, done.stderr


def test_a_robot_that_applies_a_command_at_once_gets_it_without_a_copy():
    from actions.robot.robot_capabilities import AppliesCommandAtOnce

    class AtOnce(SdkGo2):
        joint_names, leg_names = JOINT_NAMES, LEGS

        def apply_command(self, command: MotorCommand) -> None:
            self.commands.append(command)

    keeping = SdkGo2(SensorRecord.zeros())
    keeping.joint_names, keeping.leg_names = JOINT_NAMES, LEGS  # type: ignore[misc]
    at_once = AtOnce(SensorRecord.zeros())
    assert isinstance(at_once, AppliesCommandAtOnce)
    assert not isinstance(keeping, AppliesCommandAtOnce)
    command = MotorCommand.pure_torque(np.arange(12.0))
    MappedRobot(at_once).write_command(command)
    MappedRobot(keeping).write_command(command)
    assert at_once.commands == [command] and at_once.commands[0] is command
    copy = keeping.commands[0]  # a robot that may keep it gets its own arrays
    assert copy is not command and copy.tau_ff is not command.tau_ff
    assert np.array_equal(copy.tau_ff, command.tau_ff)
    # The robot is judged again when it is replaced (a test swaps in a faulty one).
    mapped = MappedRobot(at_once)
    mapped.write_command(command)
    mapped.robot = keeping
    mapped.write_command(command)
    assert keeping.commands[-1] is not command and at_once.commands[-1] is command
    assert "AppliesCommandAtOnce" in actions.robot.__all__
