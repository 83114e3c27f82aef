"""The GO2's DDS messages: type hashes, C layout and CRC, the numpy CDR codec against
cyclonedds' own serialiser, conversions, and a loopback exchange through Cyclone DDS."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import random
import time
from typing import Any

import numpy as np
import pinocchio as pin
import pytest
from cyclonedds.core import (
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.domain import Domain, DomainParticipant
from cyclonedds.idl import Endianness, IdlStruct
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from actions.dds.payload_codec import encode_message
from actions.go2.go2_interfaces import HighFiveFeedback
from actions.ros_interfaces.control_msgs import FOLLOW_JOINT_TRAJECTORY
from wbc.core.errors import ConfigurationError
from wbc.model.joint_map import JointMap
from wbc.robot_io.dds import domain_config as domain_config_module
from wbc.robot_io.dds.action_messages import GoalFeedback
from wbc.robot_io.dds.c_layout import (
    BMS_CMD_DTYPE,
    BMS_STATE_DTYPE,
    IMU_STATE_DTYPE,
    LOW_CMD_DTYPE,
    LOW_STATE_DTYPE,
    MOTOR_CMD_DTYPE,
    MOTOR_STATE_DTYPE,
    crc32_bit_by_bit,
    crc_ok,
    low_cmd_crc,
    low_state_crc,
    sdk_default_low_cmd,
    set_crc,
    zero_record,
)
from wbc.robot_io.dds.cdr_codec import CdrCodec, FrameError
from wbc.robot_io.dds.domain_config import (
    WRITER_LINGER_MS,
    DomainHandle,
    delete_entities,
    domain_config,
    host_interfaces,
    join_domain,
)
from wbc.robot_io.dds.go2_types import (
    LOW_CMD_TOPIC,
    LOW_STATE_TOPIC,
    IMUState_,
    LowCmd_,
    LowState_,
    MotorCmd_,
)
from wbc.robot_io.dds.low_cmd_conversion import (
    low_cmd_fault,
    low_cmd_from_sdk_command,
    motor_command_from_low_cmd,
    sdk_command_from_low_cmd,
)
from wbc.robot_io.dds.low_cmd_frame import LowCmdFrame
from wbc.robot_io.dds.low_state_conversion import (
    low_state_from_sensor_record,
    rpy_from_wxyz,
    sensor_record_from_low_state,
)
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_low_state import sensor_record_from_message
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.sensor_record import SensorRecord
from wbc.robot_io.unitree_sdk import MODE_ENABLE, POS_STOP_F, VEL_STOP_F

MESSAGES = [(LowCmd_, LowCmdMessage, LOW_CMD_DTYPE), (LowState_, LowStateMessage, LOW_STATE_DTYPE)]
VERSIONS = [1, 2]


# --- helpers --------------------------------------------------------------------------------

def random_record(dtype: np.dtype, rng: np.random.Generator) -> np.ndarray:
    """Random bytes in every field, finite floats, zero padding (as a C++ message)."""
    noisy = np.zeros((), dtype)
    np.frombuffer(noisy, np.uint8)[:] = rng.integers(0, 256, dtype.itemsize)

    def finite_floats(array: np.ndarray) -> None:
        for name in array.dtype.names:
            values = array[name]
            if values.dtype.names:
                finite_floats(values)
            elif values.dtype.kind == "f":
                values[...] = rng.normal(scale=100.0, size=values.shape)

    def copy_fields(target: np.ndarray, source: np.ndarray) -> None:
        for name in source.dtype.names:  # primitive by primitive: the padding stays zero
            if source.dtype[name].names or (source.dtype[name].subdtype is not None
                                            and source.dtype[name].subdtype[0].names):
                copy_fields(target[name], source[name])
            else:
                target[name] = source[name]

    finite_floats(noisy)
    record = np.zeros((), dtype)
    copy_fields(record, noisy)
    return record


def to_idl(cls: type, record: Any) -> Any:
    """The IdlStruct instance of a record, built field by field (independent of the codec)."""
    prototype = cls()
    values = {}
    for name in record.dtype.names:
        value = np.asarray(record[name])
        default = getattr(prototype, name)
        if value.dtype.names and isinstance(default, list):
            values[name] = [to_idl(type(default[0]), element) for element in value]
        elif value.dtype.names:
            values[name] = to_idl(type(default), value)
        else:
            values[name] = value.tolist()
    return cls(**values)


# --- types ----------------------------------------------------------------------------------

@pytest.mark.parametrize(("idl_type", "prefix"), [
    (MotorCmd_, "c8e5835b0f0c1765bc231dfa02ff"),
    (LowCmd_, "832876ceec9737d69f6ed62a3f63"),
    (LowState_, "853a99e23d0daa1610b65c526b40"),
    (IMUState_, "4b1bf4af32e5bc6710efc8293115"),
])
def test_minimal_type_hashes_equal_the_cpp_headers(idl_type, prefix):
    type_id = idl_type.__idl__.get_type_info().minimal.typeid_with_size.type_id
    assert type_id.equivalence_hash.hex().startswith(prefix)


def test_type_names_and_topics():
    assert LowCmd_.__idl__.idl_transformed_typename == "unitree_go::msg::dds_::LowCmd_"
    assert LowState_.__idl__.idl_transformed_typename == "unitree_go::msg::dds_::LowState_"
    assert (LOW_CMD_TOPIC, LOW_STATE_TOPIC) == ("rt/lowcmd", "rt/lowstate")


def test_wire_messages_register_exactly_the_idl_types():
    for idl_type, message, _ in MESSAGES:
        assert message.__idl__ is idl_type.__idl__


# --- C layout and CRC -----------------------------------------------------------------------

def test_c_sizes_match_the_cpp_classes():
    sizes = [d.itemsize for d in (MOTOR_CMD_DTYPE, BMS_CMD_DTYPE, LOW_CMD_DTYPE,
                                  IMU_STATE_DTYPE, MOTOR_STATE_DTYPE, BMS_STATE_DTYPE,
                                  LOW_STATE_DTYPE)]
    assert sizes == [36, 4, 812, 56, 48, 44, 1180]


def test_crc_test_vectors():
    assert low_cmd_crc(sdk_default_low_cmd()) == 0x06E577CD
    assert low_cmd_crc(np.zeros((), LOW_CMD_DTYPE)) == 0x4B5A4880
    assert low_state_crc(np.zeros((), LOW_STATE_DTYPE)) == 0x85F11EA6
    # The bit-by-bit reference gives the published vectors too.
    assert crc32_bit_by_bit(np.frombuffer(sdk_default_low_cmd(), np.uint32)[:-1]) == 0x06E577CD


@pytest.mark.parametrize("dtype", [LOW_CMD_DTYPE, LOW_STATE_DTYPE])
def test_table_crc_equals_the_bit_loop(dtype):
    record = random_record(dtype, np.random.default_rng(3))
    words = np.frombuffer(record, np.uint32)[:-1]
    assert len(words) == {LOW_CMD_DTYPE: 202, LOW_STATE_DTYPE: 294}[dtype]
    assert set_crc(record) == crc32_bit_by_bit(words) == int(record["crc"])
    assert crc_ok(record)


@pytest.mark.parametrize("dtype", [LOW_CMD_DTYPE, LOW_STATE_DTYPE])
def test_any_flipped_bit_fails_the_crc(dtype):
    rng = np.random.default_rng(4)
    record = random_record(dtype, rng)
    set_crc(record)
    raw = np.frombuffer(record, np.uint8)
    for byte in rng.integers(0, dtype.itemsize - 4, 20):
        corrupted = record.copy()
        np.frombuffer(corrupted, np.uint8)[byte] ^= np.uint8(1 << int(rng.integers(8)))
        assert not crc_ok(corrupted)
    assert crc_ok(record) and raw.sum() > 0


def test_sdk_default_low_cmd():
    record = sdk_default_low_cmd()
    assert record["head"].tolist() == [0xFE, 0xEF] and record["level_flag"] == 0xFF
    motors = record["motor_cmd"]
    assert np.all(motors["mode"] == MODE_ENABLE)
    assert np.all(motors["q"] == np.float32(POS_STOP_F))
    assert np.all(motors["dq"] == np.float32(VEL_STOP_F))
    assert not motors["kp"].any() and not motors["kd"].any() and not motors["tau"].any()
    assert record["crc"] == 0x06E577CD


def test_crc_of_something_else_names_the_layout():
    with pytest.raises(ConfigurationError, match=r"^LowCmd_: expected a 0-d NumPy array of "
                       r"the LowCmd_ C layout \(812 B, wbc.robot_io.dds.c_layout\), received "
                       r"an array of dtype float64 and shape \(203,\)$"):
        low_cmd_crc(np.zeros(203))
    with pytest.raises(ConfigurationError, match="received an array of dtype"):
        set_crc(np.zeros((), MOTOR_CMD_DTYPE))


# --- CDR codec ------------------------------------------------------------------------------

@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize(("idl_type", "message", "dtype"), MESSAGES)
def test_encoding_is_byte_for_byte_cyclonedds_serialize(idl_type, message, dtype, version):
    rng = np.random.default_rng(version)
    for _ in range(10):
        record = random_record(dtype, rng)
        expected = to_idl(idl_type, record).serialize(use_version_2=version == 2)
        assert message(record).serialize(use_version_2=version == 2) == expected
        assert message._codec.message_size(version) == len(expected)


@pytest.mark.parametrize("endianness", [Endianness.Little, Endianness.Big])
@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize(("idl_type", "message", "dtype"), MESSAGES)
def test_decoding_cyclonedds_bytes_gives_the_record(idl_type, message, dtype, version,
                                                     endianness):
    rng = np.random.default_rng(10 + version)
    for _ in range(10):
        record = random_record(dtype, rng)
        data = to_idl(idl_type, record).serialize(use_version_2=version == 2,
                                                  endianness=endianness)
        padded = data + bytes(-len(data) % 4)  # as DataWriter.write pads
        decoded = message.deserialize(padded).record
        assert decoded.tobytes() == record.tobytes()


def test_decoding_a_payload_without_header():
    record = random_record(LOW_STATE_DTYPE, np.random.default_rng(13))
    for version in VERSIONS:
        payload = to_idl(LowState_, record).serialize(use_version_2=version == 2)[4:]
        decoded = LowStateMessage.deserialize(payload, has_header=False,
                                              use_version_2=version == 2)
        assert decoded.record.tobytes() == record.tobytes()


def test_feedbacks_hand_written_encodings_are_the_generic_ones_byte_for_byte():
    """GoalFeedback's XCDR1 message (written by hand) and a feedback's JSON (flat fields as they
    are) equal cyclonedds' generic serialiser's and ``json.dumps`` of ``dataclasses.asdict``'s,
    on seeded random text (multi-byte UTF-8, every string length mod 4) and stamps."""
    rng = random.Random(11)
    alphabet = "abcXYZ019 {}\":,._-\u00e9\u20ac\U0001f600"
    for _ in range(500):
        texts = ["".join(rng.choice(alphabet) for _ in range(rng.randint(0, 40)))
                 for _ in range(3)]
        stamp = rng.choice([0.0, -1.5, math.nan, 1e300, rng.uniform(-1e6, 1e6)])
        sample = GoalFeedback(*texts, stamp)
        for version in (None, False, True):
            assert sample.serialize(use_version_2=version) == IdlStruct.serialize(
                sample, use_version_2=version)
        assert GoalFeedback.deserialize(sample.serialize()).feedback == texts[2]
        feedback = HighFiveFeedback(phase=texts[0], progress=rng.random())
        assert encode_message(feedback, HighFiveFeedback, what="feedback") == json.dumps(
            dataclasses.asdict(feedback), separators=(",", ":"))
    nested = FOLLOW_JOINT_TRAJECTORY.Feedback()  # nested messages go through asdict
    assert encode_message(nested, FOLLOW_JOINT_TRAJECTORY.Feedback, what="feedback") == (
        json.dumps(dataclasses.asdict(nested.validated_copy()), separators=(",", ":")))


def test_default_sample_serializes_as_the_idl_default():
    for idl_type, message, _ in MESSAGES:
        assert message().serialize() == idl_type().serialize()
        assert message().serialize(use_version_2=True) == idl_type().serialize(use_version_2=True)


def test_cdr_dtype_reads_the_fields_of_a_message():
    record = random_record(LOW_STATE_DTYPE, np.random.default_rng(5))
    codec = LowStateMessage._codec
    for version in VERSIONS:
        data = to_idl(LowState_, record).serialize(use_version_2=version == 2)
        view = np.frombuffer(data, codec.cdr_dtype(version))[0]
        assert view["motor_state[3].q"] == record["motor_state"]["q"][3]
        assert view["imu_state.quaternion"].tolist() == record["imu_state"]["quaternion"].tolist()
        assert view["crc"] == record["crc"]
    # The CDR layout parts from the C image at motor_cmd[0].mode (byte 22 of the payload).
    offsets = CdrCodec(LOW_CMD_DTYPE, "LowCmd_").cdr_dtype(1).fields
    assert offsets["motor_cmd[0].mode"][1] - 4 == 22
    assert LOW_CMD_DTYPE.fields["motor_cmd"][1] == 24


def test_idl_round_trip():
    record = random_record(LOW_CMD_DTYPE, np.random.default_rng(6))
    sample = LowCmdMessage(record)
    assert LowCmdMessage.from_idl(sample.to_idl()) == sample


def test_decoding_rejects_malformed_messages():
    data = LowCmd_().serialize()
    with pytest.raises(FrameError, match=r"^LowCmd_: expected 812 B of XCDR1 \(\+ up to 3 B "
                       r"of padding\), received 808 B$"):
        LowCmdMessage.deserialize(data[:-4])
    with pytest.raises(FrameError, match=r"^LowCmd_: encapsulation: expected one of 0x0000, "
                       r"0x0001, 0x0006, 0x0007 .*, received 0x0009$"):
        LowCmdMessage.deserialize(b"\x00\x09" + data[2:])
    v2 = bytearray(LowState_().serialize(use_version_2=True))
    v2[84:88] = (959).to_bytes(4, "little")  # motor_state's DHEADER (payload byte 80)
    with pytest.raises(FrameError, match=r"^LowState_.motor_state: expected an XCDR2 length "
                       r"header of 960 B, received 959$"):
        LowStateMessage.deserialize(bytes(v2))


def test_message_refuses_a_record_of_the_other_type():
    with pytest.raises(ConfigurationError, match=r"^record: expected a 0-d NumPy array of "
                       r"the LowState_ C layout"):
        LowStateMessage(np.zeros((), LOW_CMD_DTYPE))


# --- conversions ----------------------------------------------------------------------------

def random_sensor_record(rng: np.random.Generator) -> SensorRecord:
    quat = rng.normal(size=4)
    return SensorRecord(
        stamp_s=1.0, tick=int(rng.integers(0, 2**32)),
        imu_quaternion_wxyz=quat / np.linalg.norm(quat), gyroscope_rad_s=rng.normal(size=3),
        accelerometer_m_s2=rng.normal(size=3), q=rng.uniform(-2, 2, 12), dq=rng.normal(size=12),
        tau_est=rng.normal(size=12), foot_force=rng.integers(-300, 300, 4).astype(float))


def assert_same_sensor_values(a: SensorRecord, b: SensorRecord) -> None:
    for name in ("imu_quaternion_wxyz", "gyroscope_rad_s", "accelerometer_m_s2", "q", "dq",
                 "tau_est"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-6, atol=1e-6,
                                   err_msg=name)
    np.testing.assert_array_equal(a.foot_force, b.foot_force)
    assert a.tick == b.tick


def test_sensor_record_round_trip_through_a_low_state():
    rng = np.random.default_rng(7)
    reused = SensorRecord.zeros()
    for _ in range(5):
        sensor = random_sensor_record(rng)
        record = low_state_from_sensor_record(sensor)
        assert crc_ok(record) and record["head"].tolist() == [0xFE, 0xEF]
        back = sensor_record_from_low_state(record)
        assert_same_sensor_values(sensor, back)
        assert back.stamp_s == pytest.approx(sensor.tick * 1e-3)
        assert sensor_record_from_low_state(record, stamp_s=2.5, out=reused) is reused
        assert_same_sensor_values(sensor, reused)
        assert reused.stamp_s == 2.5


def test_the_compiled_read_into_a_buffer_equals_the_array_path():
    """Into the loop's buffer, the conversion is one compiled gather; it gives what NumPy's
    field views give (a new record), bit for bit, NaN and infinities included; a buffer whose
    vector has another length goes the NumPy way and is named."""
    rng = np.random.default_rng(12)
    buffer = SensorRecord.zeros()
    for k in range(20):
        record = random_record(LOW_STATE_DTYPE, rng)
        if k % 4 == 0:  # non-finite readings pass through to the estimator
            record["motor_state"]["dq"][rng.integers(0, 12)] = np.nan
            record["imu_state"]["gyroscope"][rng.integers(0, 3)] = -np.inf
        expected = sensor_record_from_low_state(record)
        got = sensor_record_from_low_state(record, out=buffer)
        for name in ("imu_quaternion_wxyz", "gyroscope_rad_s", "accelerometer_m_s2", "q", "dq",
                     "tau_est", "foot_force"):
            np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
        assert (got.tick, got.stamp_s) == (expected.tick, expected.stamp_s)
    buffer.q = np.zeros(13)
    with pytest.raises(ValueError, match="shape"):
        sensor_record_from_low_state(record, out=buffer)


def test_low_state_mapping_equals_the_sdk_message_reader():
    record = random_record(LOW_STATE_DTYPE, np.random.default_rng(8))
    idl = LowStateMessage(record).to_idl()
    expected = sensor_record_from_message(idl)
    got = sensor_record_from_low_state(record)
    assert_same_sensor_values(expected, got)
    assert got.stamp_s == expected.stamp_s


def test_low_state_orders_and_rpy():
    sensor = SensorRecord.zeros()
    sensor.q[:] = np.arange(12)  # description order FL, FR, RL, RR
    sensor.foot_force[:] = [1, 2, 3, 4]  # FL, FR, RL, RR
    sensor.imu_quaternion_wxyz[:] = pin.Quaternion(pin.rpy.rpyToMatrix(0.1, -0.2, 0.3)).coeffs()[
        [3, 0, 1, 2]]
    record = low_state_from_sensor_record(sensor)
    sdk = JointMap.unitree_sdk()
    assert record["motor_state"]["q"][:12].tolist() == sdk.to_other(sensor.q).tolist()
    assert record["motor_state"]["q"][:12].tolist()[:3] == [3, 4, 5]  # FR first
    assert record["foot_force"].tolist() == [2, 1, 4, 3]  # FR, FL, RR, RL
    np.testing.assert_allclose(record["imu_state"]["rpy"], [0.1, -0.2, 0.3], atol=1e-6)
    np.testing.assert_allclose(rpy_from_wxyz(sensor.imu_quaternion_wxyz), [0.1, -0.2, 0.3])


def test_foot_force_is_rounded_and_clipped_to_int16():
    sensor = SensorRecord.zeros()
    sensor.foot_force[:] = [np.nan, 1e9, -1e9, 2.6]  # FL, FR, RL, RR
    record = low_state_from_sensor_record(sensor)
    assert record["foot_force"].tolist() == [32767, 0, 3, -32768]


def random_sdk_command(rng: np.random.Generator) -> SdkMotorCommand:
    kp = rng.uniform(1.0, 60.0, 12)
    kp[:3] = 0.0
    cmd = MotorCommand(q_des=rng.uniform(-2.0, 2.0, 12), dq_des=rng.normal(size=12), kp=kp,
                       kd=rng.uniform(0.5, 5.0, 12), tau_ff=rng.uniform(-20.0, 20.0, 12))
    return SdkMotorCommand.from_control_output(cmd)


def test_sdk_command_round_trip_through_a_low_cmd():
    rng = np.random.default_rng(9)
    reused = sdk_default_low_cmd()
    for _ in range(5):
        command = random_sdk_command(rng)
        record = low_cmd_from_sdk_command(command)
        assert low_cmd_fault(record) is None and crc_ok(record)
        back = sdk_command_from_low_cmd(record)
        for name in ("q", "dq", "tau", "kp", "kd"):
            np.testing.assert_allclose(getattr(back, name), getattr(command, name), rtol=1e-6,
                                       atol=1e-6, err_msg=name)
        np.testing.assert_array_equal(back.mode, command.mode)
        assert np.all(back.q[command.kp == 0.0] == np.float32(POS_STOP_F))
        # All 20 slots as SdkMotorCommand.as_20_slots (and write_to) has them: slots 12 to 19
        # idle as the SDK sends them, enabled with the stop sentinels.
        slots = command.as_20_slots()
        for name, values in slots.items():
            np.testing.assert_array_equal(record["motor_cmd"][name],
                                          values.astype(record["motor_cmd"][name].dtype),
                                          err_msg=name)
        idle = record["motor_cmd"][12:]
        assert np.all(idle["mode"] == MODE_ENABLE) and np.all(idle["q"] == np.float32(POS_STOP_F))
        assert np.all(idle["dq"] == np.float32(VEL_STOP_F)) and not np.any(idle["kp"])
        reused["motor_cmd"][12:] = 0  # whatever the caller left there is replaced
        assert low_cmd_from_sdk_command(command, out=reused) is reused
        assert reused.tobytes() == record.tobytes()


def test_bad_command_frames_are_named():
    record = low_cmd_from_sdk_command(random_sdk_command(np.random.default_rng(10)))
    bad_head = record.copy()
    bad_head["head"] = [0xFE, 0xEE]
    assert low_cmd_fault(bad_head) == "LowCmd_.head: expected FE EF (the SDK's), received FE EE"
    bad_level = record.copy()
    bad_level["level_flag"] = 0xEE
    assert (low_cmd_fault(bad_level)
            == "LowCmd_.level_flag: expected 0xFF (low level), received 0xEE")
    bad_crc = record.copy()
    bad_crc["motor_cmd"]["kp"][5] += 1.0
    expected_crc = low_cmd_crc(bad_crc)
    assert low_cmd_fault(bad_crc) == (
        f"LowCmd_.crc: expected 0x{expected_crc:08X} (CRC-32/MPEG-2 of the first 202 words), "
        f"received 0x{int(record['crc']):08X}")
    with pytest.raises(FrameError, match=r"^LowCmd_\.crc: expected 0x"):
        sdk_command_from_low_cmd(bad_crc)
    negative = record.copy()
    negative["motor_cmd"]["kd"][2] = -1.0
    set_crc(negative)
    with pytest.raises(FrameError, match=r"^LowCmd_\.motor_cmd\[0\.\.11\]: kd: expected gains "
                       r">= 0, received \[-1\.0\] at 2 \(FR_calf_joint\)$"):
        sdk_command_from_low_cmd(negative)


def checked_low_cmd(command: MotorCommand, reserve: int,
                    use_stop_sentinels: bool = True) -> np.ndarray:
    """The record of the checked path: SdkMotorCommand, then low_cmd_from_sdk_command."""
    record = sdk_default_low_cmd()
    record["reserve"] = reserve
    sdk = SdkMotorCommand.from_control_output(command, use_stop_sentinels=use_stop_sentinels)
    return low_cmd_from_sdk_command(sdk, out=record)


def random_command(rng: np.random.Generator) -> MotorCommand:
    """A description-order command, some gains zero (the stop sentinels), one of them -0."""
    kp, kd = rng.uniform(0.0, 60.0, 12), rng.uniform(0.0, 3.0, 12)
    kp[rng.random(12) < 0.3] = 0.0
    kd[rng.random(12) < 0.3] = 0.0
    kp[4] = -0.0
    return MotorCommand(q_des=rng.normal(0.0, 2.0, 12), dq_des=rng.normal(0.0, 20.0, 12),
                        kp=kp, kd=kd, tau_ff=rng.normal(0.0, 15.0, 12))


@pytest.mark.parametrize("use_stop_sentinels", [True, False])
def test_low_cmd_frame_writes_the_bytes_of_the_checked_path(use_stop_sentinels):
    rng = np.random.default_rng(21)
    frame = LowCmdFrame(use_stop_sentinels=use_stop_sentinels)
    for reserve in [0, 1, 41, 2**32 - 1, *rng.integers(0, 2**32, 300).tolist()]:
        command = random_command(rng)
        assert frame.fill(command, reserve=reserve)
        assert frame.record.tobytes() == checked_low_cmd(
            command, reserve, use_stop_sentinels).tobytes()
    assert low_cmd_fault(frame.record) is None


def test_low_cmd_frame_refuses_what_the_checked_path_refuses_and_writes_nothing():
    frame = LowCmdFrame()
    good = random_command(np.random.default_rng(22))
    assert frame.fill(good, reserve=7)
    sent = frame.record.tobytes()

    def changed(field: str, index: int, value: float) -> MotorCommand:
        bad = good.copy()
        getattr(bad, field)[index] = value
        return bad

    bad_commands = [changed("tau_ff", 3, np.nan), changed("q_des", 0, np.inf),
                    changed("kp", 2, -1.0), changed("kd", 11, -1e-9),
                    changed("q_des", 5, POS_STOP_F), changed("dq_des", 6, VEL_STOP_F)]
    bad_commands[4].kp[5] = bad_commands[5].kd[6] = 1.0  # a sentinel under a gain
    short = good.copy()
    short.kp = short.kp[:11]
    for bad in [*bad_commands, short]:
        with pytest.raises(ConfigurationError):
            SdkMotorCommand.from_control_output(bad)
        assert not frame.fill(bad, reserve=8)
        assert frame.record.tobytes() == sent  # nothing written
    # Another dtype is left to the checked path, which converts it.
    as_float32 = MotorCommand(**{name: np.asarray(getattr(good, name), np.float32)
                                 for name in ("q_des", "dq_des", "kp", "kd", "tau_ff")})
    assert not frame.fill(as_float32) and frame.record.tobytes() == sent
    SdkMotorCommand.from_control_output(as_float32)


def spoiled_low_cmd(rng: np.random.Generator) -> tuple[np.ndarray, str]:
    """A received-like (read-only) LowCmd_ record with, most of the time, one thing wrong."""
    record = low_cmd_from_sdk_command(random_sdk_command(rng))
    motors = record["motor_cmd"]
    slot = int(rng.integers(0, 12))
    fault = str(rng.choice(["none", "stopped motor", "mode", "nan", "gain", "sentinel", "tau",
                            "crc", "head", "level_flag"]))
    if fault == "stopped motor":
        motors["mode"][slot] = 0
    elif fault == "mode":
        motors["mode"][slot] = 2
    elif fault == "nan":
        motors[str(rng.choice(["q", "dq", "tau", "kp", "kd"]))][slot] = np.nan
    elif fault == "gain":
        motors[str(rng.choice(["kp", "kd"]))][slot] = -0.5
    elif fault == "sentinel":
        motors["q"][slot] = POS_STOP_F
        motors["kp"][slot] = 10.0
    elif fault == "tau":
        motors["tau"][slot] = 30.0
    elif fault == "head":
        record["head"][1] = 0xEE
    elif fault == "level_flag":
        record["level_flag"] = 0xEE
    set_crc(record)
    if fault == "crc":
        record["crc"] ^= 1 << int(rng.integers(0, 32))
    received = np.ndarray((), dtype=LOW_CMD_DTYPE, buffer=record.tobytes())  # read-only
    return received, fault


def checked_driver_command(record: np.ndarray, slots: np.ndarray,
                           effort_limit: np.ndarray) -> MotorCommand | None:
    """The checked way: the robot's checks, SdkMotorCommand, the driver's effort limits."""
    try:
        sdk = sdk_command_from_low_cmd(record)
    except FrameError:
        return None
    command = sdk.to_motor_command().reordered(JointMap.unitree_sdk().index[slots])
    return None if command.problems(effort_limit) else command


def test_the_compiled_driver_command_equals_the_checked_path():
    rng = np.random.default_rng(23)
    slots = rng.permutation(12).astype(np.intp)  # any joint order, mapped by slot
    effort_limit = np.full(12, 23.7)
    seen = set()
    for _ in range(600):
        record, fault = spoiled_low_cmd(rng)
        fast = motor_command_from_low_cmd(record, slots=slots, effort_limit=effort_limit)
        checked = checked_driver_command(record, slots, effort_limit)
        assert (fast is None) == (checked is None), fault
        assert (fast is None) == (fault not in ("none", "stopped motor")), fault
        seen.add(fault)
        if fast is not None:
            for name in ("q_des", "dq_des", "kp", "kd", "tau_ff"):
                np.testing.assert_array_equal(getattr(fast, name), getattr(checked, name),
                                              err_msg=f"{fault}: {name}")
    assert len(seen) == 10
    with pytest.raises(ConfigurationError, match="expected a 0-d NumPy array of the LowCmd_"):
        motor_command_from_low_cmd(zero_record(LOW_STATE_DTYPE), slots=slots,
                                   effort_limit=effort_limit)


# --- domain configuration -------------------------------------------------------------------

def test_domain_config_binds_one_interface(monkeypatch):
    xml = domain_config("lo", domain_id=150)
    assert '<Domain id="150">' in xml
    assert '<NetworkInterface name="lo" multicast="false"/>' in xml
    assert f"<WriterLingerDuration>{WRITER_LINGER_MS}ms</WriterLingerDuration>" in xml
    assert 'multicast="true"' in domain_config("lo", domain_id=0, multicast=True)
    # Off loopback, Cyclone's default (multicast discovery across machines).
    monkeypatch.setattr(domain_config_module, "is_loopback", lambda interface: False)
    assert '<NetworkInterface name="lo" multicast="default"/>' in domain_config("lo", domain_id=0)


def test_domain_config_errors():
    with pytest.raises(ConfigurationError) as err:
        domain_config("nosuch0", domain_id=1)
    assert str(err.value) == (f"interface: expected one of this host's network interfaces "
                              f"{host_interfaces()}, received 'nosuch0'")
    assert "lo" in host_interfaces()
    with pytest.raises(ConfigurationError, match=r"^domain_id: expected 0\.\.232 \(the default "
                       r"RTPS port mapping\), received 233 \(the GO2 uses 0, unitree_mujoco "
                       r"1\)$"):
        domain_config("lo", domain_id=233)
    for bad in (-1, True, "1"):
        with pytest.raises(ConfigurationError, match=r"^domain_id: expected"):
            domain_config("lo", domain_id=bad)


# --- loopback through Cyclone DDS -----------------------------------------------------------

def private_domain_id() -> int:
    """A domain of this test process alone (concurrent test runs stay apart)."""
    return 150 + os.getpid() % 80


@pytest.fixture
def loopback():
    """Two participants on a private domain bound to ``lo``; entities deleted children first."""
    entities: list[Any] = []
    with join_domain("lo", domain_id=private_domain_id()) as first, \
            join_domain("lo", domain_id=private_domain_id()) as second:
        yield first.participant, second.participant, entities
        delete_entities(*reversed(entities))  # readers and writers, last created first


def receive_one(participant: DomainParticipant, reader: DataReader) -> Any:
    waitset = WaitSet(participant)
    waitset.attach(ReadCondition(reader, SampleState.Any | ViewState.Any | InstanceState.Any))
    waitset.wait(duration(seconds=1))
    samples = reader.take()
    assert len(samples) == 1
    return samples[0]


def test_loopback_exchange_with_idl_peers(loopback):
    first, second, entities = loopback
    start = time.perf_counter()
    # Reliable + transient-local: a sample written before discovery completes still arrives.
    qos = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
              Policy.Durability.TransientLocal, Policy.History.KeepLast(1))

    # State: the fast class writes, an IdlStruct peer reads (the default: XCDR1).
    state_writer = DataWriter(first, Topic(first, LOW_STATE_TOPIC, LowStateMessage), qos=qos)
    state_reader = DataReader(second, Topic(second, LOW_STATE_TOPIC, LowState_), qos=qos)
    entities += [state_writer, state_reader]
    assert state_writer.get_qos()[Policy.DataRepresentation] == Policy.DataRepresentation(
        use_cdrv0_representation=True, use_xcdrv2_representation=False)
    sensor = random_sensor_record(np.random.default_rng(11))
    state_writer.write(LowStateMessage(low_state_from_sensor_record(sensor)))
    state = receive_one(second, state_reader)
    assert isinstance(state, LowState_)
    assert_same_sensor_values(sensor, sensor_record_from_message(state))

    # Command: an IdlStruct peer writes XCDR2, the fast class reads.
    xcdr2 = Qos(Policy.DataRepresentation(use_xcdrv2_representation=True), base=qos)
    cmd_writer = DataWriter(second, Topic(second, LOW_CMD_TOPIC, LowCmd_), qos=xcdr2)
    cmd_reader = DataReader(first, Topic(first, LOW_CMD_TOPIC, LowCmdMessage), qos=xcdr2)
    entities += [cmd_writer, cmd_reader]
    command = random_sdk_command(np.random.default_rng(12))
    cmd_writer.write(LowCmdMessage(low_cmd_from_sdk_command(command)).to_idl())
    received = receive_one(first, cmd_reader)
    assert isinstance(received, LowCmdMessage) and received.sample_info.valid_data
    np.testing.assert_allclose(sdk_command_from_low_cmd(received.record).kp, command.kp,
                               rtol=1e-6)
    assert time.perf_counter() - start < 1.0


def test_handles_of_a_domain_id_share_one_configuration():
    domain_id = private_domain_id()
    first = join_domain("lo", domain_id=domain_id)
    try:
        with join_domain("lo", domain_id=domain_id, multicast=False) as second:
            assert isinstance(second, DomainHandle) and second.interface == "lo"
            assert second.participant.domain_id == first.participant.domain_id == domain_id
            with pytest.raises(ConfigurationError) as err:
                join_domain("lo", domain_id=domain_id, multicast=True)
            assert str(err.value) == (
                f"interface: domain {domain_id} is already configured in this process for "
                f"interface 'lo' (multicast false), received a request for interface 'lo' "
                f"(multicast true); Cyclone DDS takes one configuration per domain id and "
                f"process: join domain {domain_id} with interface 'lo' (multicast false), use "
                f"another domain id, or close its 2 open DomainHandle(s) first")
        # The first handle still holds the configuration: its participant keeps working.
        assert first.participant.domain_id == domain_id
    finally:
        first.close()
    first.close()  # idempotent
    assert first.is_closed
    with pytest.raises(ConfigurationError, match=rf"^participant: the DomainHandle of domain "
                       rf"{domain_id} is closed"):
        _ = first.participant
    # Every handle closed: the domain id can be configured again, differently.
    with join_domain("lo", domain_id=domain_id, multicast=True) as again:
        assert again.participant.domain_id == domain_id


def test_a_domain_configured_outside_join_domain_is_named():
    domain_id = private_domain_id()
    outside = Domain(domain_id, domain_config("lo", domain_id=domain_id))
    try:
        with pytest.raises(ConfigurationError, match=rf"^domain_id: domain {domain_id} is "
                           r"already configured in this process outside join_domain"):
            join_domain("lo", domain_id=domain_id)
    finally:
        delete_entities(outside)
    with join_domain("lo", domain_id=domain_id) as dds:  # a failed join leaked nothing
        assert dds.participant.domain_id == domain_id
