"""Joint and leg orders carried by records and commands, and checked by every conversion."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from tests.synthetic_records import pose, record
from wbc.core.errors import ConfigurationError, OrderMismatchError
from wbc.estimation.estimators import make_estimator
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS, Orders
from wbc.robot_io.dds.c_layout import LOW_CMD_DTYPE, LOW_STATE_DTYPE, zero_record
from wbc.robot_io.dds.low_cmd_conversion import (
    low_cmd_from_sdk_command,
    motor_command_from_low_cmd,
)
from wbc.robot_io.dds.low_cmd_frame import LowCmdFrame
from wbc.robot_io.dds.low_state_conversion import (
    low_state_from_sensor_record,
    sensor_record_from_low_state,
)
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_low_state import SdkLowState, sensor_record_from_message
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.sensor_record import SensorRecord

SDK = "the Unitree SDK's orders (joints and feet by leg FR, FL, RR, RL)"
DESCRIPTION = "the description's orders (joints and feet by leg FL, FR, RL, RR)"
SDK_JOINTS = "the Unitree SDK's joint order (by leg FR, FL, RR, RL)"
DESCRIPTION_JOINTS = "the description's joint order (by leg FL, FR, RL, RR)"
COMMAND_FIX = ("pass the controller's command as it is (the description's order): this "
               "conversion maps it to the SDK's by name")
RECORD_FIX = ("map it by name first (a ControlLoop does, through MappedRobot, for a robot "
              "that declares its joint_names and leg_names)")


def message_of(error: pytest.ExceptionInfo) -> str:
    return str(error.value)


def a_command(orders: Orders = DESCRIPTION_ORDERS) -> MotorCommand:
    """A command a driver takes: distinct values per joint, so that any swap shows."""
    joints = np.arange(12.0)
    return MotorCommand(q_des=0.1 * joints, dq_des=0.01 * joints, kp=20.0 + joints,
                        kd=0.5 + 0.1 * joints, tau_ff=joints - 6.0, orders=orders)


# --------------------------------------------------------------------------- the orders


def test_orders_are_interned_and_compared_by_names_not_by_label():
    assert Orders.of(JOINT_NAMES, LEGS) is DESCRIPTION_ORDERS
    assert Orders.of(list(UNITREE_SDK_JOINT_NAMES), UNITREE_SDK_LEGS) is UNITREE_SDK_ORDERS
    built = Orders(UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS, name="mine")  # not interned
    assert built is not UNITREE_SDK_ORDERS
    assert built == UNITREE_SDK_ORDERS and hash(built) == hash(UNITREE_SDK_ORDERS)
    assert DESCRIPTION_ORDERS != UNITREE_SDK_ORDERS
    assert pickle.loads(pickle.dumps(UNITREE_SDK_ORDERS)) is UNITREE_SDK_ORDERS
    with pytest.raises(AttributeError, match="^Orders are immutable: cannot set leg_names$"):
        DESCRIPTION_ORDERS.leg_names = UNITREE_SDK_LEGS  # type: ignore[misc]


def test_orders_describe_themselves_by_leg():
    assert DESCRIPTION_ORDERS.describe() == DESCRIPTION
    assert UNITREE_SDK_ORDERS.describe(legs=False) == SDK_JOINTS
    mixed = Orders.of(UNITREE_SDK_JOINT_NAMES, LEGS, name="the bridge's raw")
    assert mixed.describe() == ("the bridge's raw orders (joints by leg FR, FL, RR, RL; "
                                "feet FL, FR, RL, RR)")
    shuffled = (*JOINT_NAMES[1:], JOINT_NAMES[0])  # not leg by leg: the names are listed
    assert Orders.of(shuffled, LEGS).describe(legs=False) == (
        f"other joint order ({', '.join(shuffled)})")


def test_orders_refuse_names_that_are_not_the_go2s():
    with pytest.raises(ConfigurationError, match=r"^joint_names: expected 12 joint names, "
                                                 r"received \['FL_hip_joint'\]$"):
        Orders(("FL_hip_joint",), LEGS)
    with pytest.raises(ConfigurationError, match=r"^joint_names: joint names "
                                                 r"\['FL_hip_joint'\] appear more than once$"):
        Orders(("FL_hip_joint",) * 2 + JOINT_NAMES[2:], LEGS)
    with pytest.raises(ConfigurationError, match=r"^leg_names: expected each of FL, FR, RL, RR "
                                                 r"once, received \['FL', 'FR', 'RL', 'XX'\]$"):
        Orders(JOINT_NAMES, ("FL", "FR", "RL", "XX"))
    with pytest.raises(ConfigurationError, match=r"^leg_names: expected 4 leg names, "
                                                 r"received 'FLFRRLRR'$"):
        Orders(JOINT_NAMES, "FLFRRLRR")


def test_a_reordering_names_its_result_and_is_cached():
    sdk = JointMap.unitree_sdk()
    assert DESCRIPTION_ORDERS.reordered(sdk.index) is UNITREE_SDK_ORDERS
    assert UNITREE_SDK_ORDERS.reordered(sdk.inverse) is DESCRIPTION_ORDERS
    swap = np.array([3, 4, 5, 0, 1, 2, 6, 7, 8, 9, 10, 11])  # FL and FR swapped
    first = DESCRIPTION_ORDERS.reordered(swap)
    assert first is DESCRIPTION_ORDERS.reordered(swap.copy())
    assert first.joint_names[:3] == ("FR_hip_joint", "FR_thigh_joint", "FR_calf_joint")
    assert first.leg_names == ("FR", "FL", "RL", "RR")  # the feet follow the joints


# --------------------------------------------------------------- records and commands


def test_a_record_or_command_built_without_orders_is_in_the_descriptions():
    assert SensorRecord.zeros().orders is DESCRIPTION_ORDERS
    assert a_command().orders is DESCRIPTION_ORDERS
    assert MotorCommand.pure_torque(np.zeros(12)).orders is DESCRIPTION_ORDERS
    buffer = SensorRecord.zeros(UNITREE_SDK_ORDERS)
    assert buffer.orders is UNITREE_SDK_ORDERS and buffer.copy().orders is UNITREE_SDK_ORDERS
    target = SensorRecord.zeros()
    target.copy_from(buffer)  # values and orders
    assert target.orders is UNITREE_SDK_ORDERS
    assert a_command(UNITREE_SDK_ORDERS).copy().orders is UNITREE_SDK_ORDERS
    with pytest.raises(ConfigurationError, match=r"^orders: expected an Orders \(e\.g\. "
                                                 r"Orders\.of\(joint_names, leg_names\).*"
                                                 r"received 'sdk'$"):
        SensorRecord.zeros("sdk")  # type: ignore[arg-type]


def test_a_reordered_command_carries_its_new_order():
    command = a_command()
    sdk = command.reordered(JointMap.unitree_sdk().index)
    assert sdk.orders is UNITREE_SDK_ORDERS
    assert sdk.tau_ff[0] == command.tau_ff[JOINT_NAMES.index("FR_hip_joint")]
    back = sdk.reordered(JointMap.unitree_sdk().inverse)
    assert back.orders is DESCRIPTION_ORDERS
    np.testing.assert_array_equal(back.tau_ff, command.tau_ff)


# ---------------------------------------------------------------- the SDK's conversions


def test_the_sdk_records_are_in_the_sdks_orders_and_convert_to_the_descriptions():
    state = SdkLowState.from_pinocchio(pose(), np.zeros(18),
                                       foot_force_by_leg=dict(zip(LEGS, [1.0, 2.0, 3.0, 4.0])))
    assert SdkLowState.orders is UNITREE_SDK_ORDERS and SdkMotorCommand.orders is UNITREE_SDK_ORDERS
    for converted in (state.sensor_record(), sensor_record_from_message(state.to_message())):
        assert converted.orders is DESCRIPTION_ORDERS
        np.testing.assert_array_equal(converted.foot_force, [1.0, 2.0, 3.0, 4.0])
    assert SdkMotorCommand.from_control_output(a_command()).to_motor_command().orders is (
        DESCRIPTION_ORDERS)


def test_a_command_in_the_sdks_order_is_refused_by_the_sdk_conversion():
    command = a_command().reordered(JointMap.unitree_sdk().index)
    with pytest.raises(OrderMismatchError) as error:
        SdkMotorCommand.from_control_output(command)
    assert message_of(error) == (
        f"SdkMotorCommand.from_control_output(cmd): in {SDK_JOINTS}, expected "
        f"{DESCRIPTION_JOINTS}: {COMMAND_FIX}")


def test_a_duck_typed_command_without_orders_is_taken_in_the_descriptions():
    class Plain:  # the five arrays only, as before commands had orders
        q_des, dq_des, kp, kd, tau_ff = (np.zeros(12), np.zeros(12), np.full(12, 20.0),
                                         np.ones(12), np.arange(12.0))

    sdk = SdkMotorCommand.from_control_output(Plain())  # type: ignore[arg-type]
    assert sdk.tau[0] == JOINT_NAMES.index("FR_hip_joint")


# ---------------------------------------------------------------- the DDS conversions


def test_a_low_state_becomes_a_record_in_the_descriptions_orders_even_in_a_reused_buffer():
    state = low_state_from_sensor_record(record(pose(), tick=7))
    assert sensor_record_from_low_state(state).orders is DESCRIPTION_ORDERS
    buffer = SensorRecord.zeros(UNITREE_SDK_ORDERS)
    assert sensor_record_from_low_state(state, out=buffer) is buffer
    assert buffer.orders is DESCRIPTION_ORDERS  # refilled in the description's orders


def test_a_record_in_the_sdks_orders_is_refused_by_the_low_state_conversion():
    sdk_record = record(pose(), tick=7)
    sdk_record.orders = UNITREE_SDK_ORDERS
    out = zero_record(LOW_STATE_DTYPE)
    with pytest.raises(OrderMismatchError) as error:
        low_state_from_sensor_record(sdk_record, out=out)
    assert message_of(error) == (
        f"low_state_from_sensor_record(sensor): in {SDK}, expected {DESCRIPTION}: map the "
        "plant's record to the description's orders by name first (this conversion maps that "
        "to the SDK's)")
    assert out.tobytes() == zero_record(LOW_STATE_DTYPE).tobytes()  # nothing written


def test_a_command_in_the_sdks_order_is_refused_by_the_low_cmd_frame():
    frame = LowCmdFrame()
    before = frame.record.tobytes()
    with pytest.raises(OrderMismatchError) as error:
        frame.fill(a_command().reordered(JointMap.unitree_sdk().index))
    assert message_of(error) == (
        f"LowCmdFrame.fill(command): in {SDK_JOINTS}, expected {DESCRIPTION_JOINTS}: "
        f"{COMMAND_FIX}")
    assert frame.record.tobytes() == before
    assert frame.fill(a_command())


def test_a_received_low_cmd_gives_a_command_in_the_order_of_its_slots():
    record = low_cmd_from_sdk_command(SdkMotorCommand.from_control_output(a_command()))
    assert record.dtype == LOW_CMD_DTYPE
    limit = np.full(12, 50.0)
    in_slots = motor_command_from_low_cmd(record, slots=np.arange(12, dtype=np.intp),
                                          effort_limit=limit)
    assert in_slots.orders is UNITREE_SDK_ORDERS
    by_name = motor_command_from_low_cmd(record, slots=JointMap.unitree_sdk().index.copy(),
                                         effort_limit=limit)
    assert by_name.orders is DESCRIPTION_ORDERS
    np.testing.assert_allclose(by_name.tau_ff, a_command().tau_ff)


# ------------------------------------------------------------------------ the estimator


def test_the_estimator_refuses_a_record_in_the_sdks_orders():
    estimator = make_estimator()
    sdk_record = record(pose(), tick=1)
    sdk_record.orders = UNITREE_SDK_ORDERS
    with pytest.raises(OrderMismatchError) as error:
        estimator.reset(sdk_record)
    name = type(estimator).__name__
    assert message_of(error) == (
        f"{name}.reset(record): in {SDK}, expected {DESCRIPTION}: {RECORD_FIX}")
    estimator.reset(record(pose(), tick=1))
    with pytest.raises(OrderMismatchError, match=rf"^{name}\.update\(record\): in the Unitree"):
        estimator.update(sdk_record, np.full(4, 200.0))
    assert estimator.update(record(pose(), tick=2), np.full(4, 200.0)).trusted
