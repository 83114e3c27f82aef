"""The GO2's low-level messages as Cyclone DDS IDL types: ``unitree_go::msg::dds_::LowCmd_`` and
``LowState_`` with their nested structs, field for field as in Unitree's IDL.

These classes fix what goes on the wire: the type name, the XTypes type information (whose
minimal hashes equal those of the C++ headers of unitree_sdk2) and the CDR encoding. They are
the reference the fast path (:mod:`wbc.robot_io.dds.wire_message`) is tested against; use them
directly wherever speed does not matter.

Type trap (interoperability): cyclonedds 11.0.1 maps ``types.uint8`` to XTypes ``TK_UINT8``,
while Cyclone 0.10.x and the C++ types generated for unitree_sdk2 map IDL ``uint8`` to
``TK_BYTE``. The two encode the same bytes but have different type hashes (MotorCmd_:
``63cdd366...`` with uint8, ``c8e5835b...`` with byte, the C++ one), and a 0.10.x peer given
the uint8 type information logs "invalid type object" and crashes. Every uint8 field is
therefore declared ``types.byte``.

All structs are ``@final`` with sequential member ids, as Unitree's IDL compiles them.
"""

# cyclonedds' IDL annotations (types.array[T, n], ...) are not types mypy understands without
# cyclonedds.idl.mypy_plugin; they are checked at runtime, when cyclonedds builds the type.
# mypy: disable-error-code="type-arg, valid-type, assignment"

# No `from __future__ import annotations`: cyclonedds resolves the field types from the real
# annotation objects and cannot resolve strings such as "t.byte".
from dataclasses import dataclass, field

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import autoid, final

from wbc.robot_io.unitree_sdk import SDK_MOTOR_SLOTS

#: The robot's state topic (``LowState_``), published by the robot at 500 Hz.
LOW_STATE_TOPIC = "rt/lowstate"
#: The command topic (``LowCmd_``), read by the robot.
LOW_CMD_TOPIC = "rt/lowcmd"

def _zeros(count: int) -> list[int]:
    return [0] * count


def _zeros_f(count: int) -> list[float]:
    return [0.0] * count


@dataclass
@final
@autoid("sequential")
class MotorCmd_(IdlStruct, typename="unitree_go.msg.dds_.MotorCmd_"):
    """One motor's command (36 B in C): mode, targets [rad, rad/s], torque [N m], gains."""

    mode: t.byte = 0
    q: t.float32 = 0.0
    dq: t.float32 = 0.0
    tau: t.float32 = 0.0
    kp: t.float32 = 0.0
    kd: t.float32 = 0.0
    reserve: t.array[t.uint32, 3] = field(default_factory=lambda: _zeros(3))


@dataclass
@final
@autoid("sequential")
class BmsCmd_(IdlStruct, typename="unitree_go.msg.dds_.BmsCmd_"):
    """The battery command (4 B in C)."""

    off: t.byte = 0
    reserve: t.array[t.byte, 3] = field(default_factory=lambda: _zeros(3))


@dataclass
@final
@autoid("sequential")
class LowCmd_(IdlStruct, typename="unitree_go.msg.dds_.LowCmd_"):
    """The low-level command, ``rt/lowcmd`` (812 B in C)."""

    head: t.array[t.byte, 2] = field(default_factory=lambda: _zeros(2))
    level_flag: t.byte = 0
    frame_reserve: t.byte = 0
    sn: t.array[t.uint32, 2] = field(default_factory=lambda: _zeros(2))
    version: t.array[t.uint32, 2] = field(default_factory=lambda: _zeros(2))
    bandwidth: t.uint16 = 0
    motor_cmd: t.array[MotorCmd_, SDK_MOTOR_SLOTS] = field(
        default_factory=lambda: [MotorCmd_() for _ in range(SDK_MOTOR_SLOTS)])
    bms_cmd: BmsCmd_ = field(default_factory=BmsCmd_)
    wireless_remote: t.array[t.byte, 40] = field(default_factory=lambda: _zeros(40))
    led: t.array[t.byte, 12] = field(default_factory=lambda: _zeros(12))
    fan: t.array[t.byte, 2] = field(default_factory=lambda: _zeros(2))
    gpio: t.byte = 0
    reserve: t.uint32 = 0
    crc: t.uint32 = 0


@dataclass
@final
@autoid("sequential")
class IMUState_(IdlStruct, typename="unitree_go.msg.dds_.IMUState_"):
    """The IMU (56 B in C): quaternion (w, x, y, z), gyroscope [rad/s], accelerometer
    [m/s^2], rpy [rad], temperature [deg C]."""

    quaternion: t.array[t.float32, 4] = field(default_factory=lambda: _zeros_f(4))
    gyroscope: t.array[t.float32, 3] = field(default_factory=lambda: _zeros_f(3))
    accelerometer: t.array[t.float32, 3] = field(default_factory=lambda: _zeros_f(3))
    rpy: t.array[t.float32, 3] = field(default_factory=lambda: _zeros_f(3))
    temperature: t.byte = 0


@dataclass
@final
@autoid("sequential")
class MotorState_(IdlStruct, typename="unitree_go.msg.dds_.MotorState_"):
    """One motor's state (48 B in C): q [rad], dq [rad/s], ddq [rad/s^2], tau_est [N m]."""

    mode: t.byte = 0
    q: t.float32 = 0.0
    dq: t.float32 = 0.0
    ddq: t.float32 = 0.0
    tau_est: t.float32 = 0.0
    q_raw: t.float32 = 0.0
    dq_raw: t.float32 = 0.0
    ddq_raw: t.float32 = 0.0
    temperature: t.byte = 0
    lost: t.uint32 = 0
    reserve: t.array[t.uint32, 2] = field(default_factory=lambda: _zeros(2))


@dataclass
@final
@autoid("sequential")
class BmsState_(IdlStruct, typename="unitree_go.msg.dds_.BmsState_"):
    """The battery state (44 B in C)."""

    version_high: t.byte = 0
    version_low: t.byte = 0
    status: t.byte = 0
    soc: t.byte = 0
    current: t.int32 = 0
    cycle: t.uint16 = 0
    bq_ntc: t.array[t.byte, 2] = field(default_factory=lambda: _zeros(2))
    mcu_ntc: t.array[t.byte, 2] = field(default_factory=lambda: _zeros(2))
    cell_vol: t.array[t.uint16, 15] = field(default_factory=lambda: _zeros(15))


@dataclass
@final
@autoid("sequential")
class LowState_(IdlStruct, typename="unitree_go.msg.dds_.LowState_"):
    """The robot's low-level state, ``rt/lowstate`` (1180 B in C)."""

    head: t.array[t.byte, 2] = field(default_factory=lambda: _zeros(2))
    level_flag: t.byte = 0
    frame_reserve: t.byte = 0
    sn: t.array[t.uint32, 2] = field(default_factory=lambda: _zeros(2))
    version: t.array[t.uint32, 2] = field(default_factory=lambda: _zeros(2))
    bandwidth: t.uint16 = 0
    imu_state: IMUState_ = field(default_factory=IMUState_)
    motor_state: t.array[MotorState_, SDK_MOTOR_SLOTS] = field(
        default_factory=lambda: [MotorState_() for _ in range(SDK_MOTOR_SLOTS)])
    bms_state: BmsState_ = field(default_factory=BmsState_)
    foot_force: t.array[t.int16, 4] = field(default_factory=lambda: _zeros(4))
    foot_force_est: t.array[t.int16, 4] = field(default_factory=lambda: _zeros(4))
    tick: t.uint32 = 0
    wireless_remote: t.array[t.byte, 40] = field(default_factory=lambda: _zeros(40))
    bit_flag: t.byte = 0
    adc_reel: t.float32 = 0.0
    temperature_ntc1: t.byte = 0
    temperature_ntc2: t.byte = 0
    power_v: t.float32 = 0.0
    power_a: t.float32 = 0.0
    fan_frequency: t.array[t.uint16, 4] = field(default_factory=lambda: _zeros(4))
    reserve: t.uint32 = 0
    crc: t.uint32 = 0
