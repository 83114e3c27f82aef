"""An :class:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand` as a ``LowCmd_`` C-image record
(:data:`~wbc.robot_io.dds.c_layout.LOW_CMD_DTYPE`) and back, with the checks the robot makes.

Out: the SDK's header (FE EF / 0xFF), motor slots 0 to 11 carry the command, slots 12 to 19
the SDK's idle command (:func:`~wbc.robot_io.unitree_sdk.set_idle_motor_slots`, the convention
of :meth:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand.write_to` too), the CRC is set. In:
a record is used only with the SDK's header and a matching CRC, as the robot drops any other;
:func:`low_cmd_fault` names what is wrong without raising.
"""

from __future__ import annotations

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.c_layout import (
    HEAD,
    LEVEL_FLAG_LOW,
    LOW_CMD_DTYPE,
    check_record,
    low_cmd_crc,
    sdk_default_low_cmd,
)
from wbc.robot_io.dds.cdr_codec import FrameError
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.unitree_sdk import SDK_LEG_MOTORS, set_idle_motor_slots

_LEGS = slice(0, SDK_LEG_MOTORS)
_HEAD = np.array(HEAD, dtype=np.uint8)
_CRC_WORDS = LOW_CMD_DTYPE.itemsize // 4 - 1


def low_cmd_from_sdk_command(command: SdkMotorCommand, *,
                             out: np.ndarray | None = None) -> np.ndarray:
    """The ``LowCmd_`` record that sends ``command``, CRC set.

    Motor slots 0 to 11 carry the command (float32 on the wire), slots 12 to 19 the SDK's
    idle command (:func:`~wbc.robot_io.unitree_sdk.set_idle_motor_slots`, as
    :meth:`SdkMotorCommand.write_to` writes them); ``head``, ``level_flag`` and the CRC are
    set; everything else keeps its value (zeros in a new record).

    Args:
        command: The 12 leg motors' command, SDK order.
        out: A record to fill in place (a control loop's, reused every tick); a new one from
            :func:`~wbc.robot_io.dds.c_layout.sdk_default_low_cmd` when not given.

    Raises:
        ConfigurationError: ``out`` is not a ``LowCmd_`` record.
    """
    if out is None:
        out = sdk_default_low_cmd()
    else:
        check_record(out, LOW_CMD_DTYPE, "out")
    out["head"] = HEAD
    out["level_flag"] = LEVEL_FLAG_LOW
    motors = out["motor_cmd"][_LEGS]
    motors["mode"] = command.mode
    motors["q"] = command.q
    motors["dq"] = command.dq
    motors["tau"] = command.tau
    motors["kp"] = command.kp
    motors["kd"] = command.kd
    set_idle_motor_slots(out["motor_cmd"])
    out["crc"] = low_cmd_crc(out)
    return out


def low_cmd_fault(record: np.ndarray) -> str | None:
    """Why the robot would drop this ``LowCmd_`` record, or ``None`` if it would take it.

    Checked in order: ``head`` (FE EF), ``level_flag`` (0xFF, low level), ``crc``. The
    reason names the field, what it holds and what is valid.

    Raises:
        ConfigurationError: ``record`` is not a ``LowCmd_`` record.
    """
    expected_crc = low_cmd_crc(record)  # checks the record first
    head = record["head"]
    if not np.array_equal(head, _HEAD):
        return (f"LowCmd_.head: expected {_hex_bytes(_HEAD)} (the SDK's), received "
                f"{_hex_bytes(head)}")
    level_flag = int(record["level_flag"])
    if level_flag != LEVEL_FLAG_LOW:
        return (f"LowCmd_.level_flag: expected 0x{LEVEL_FLAG_LOW:02X} (low level), received "
                f"0x{level_flag:02X}")
    crc = int(record["crc"])
    if crc != expected_crc:
        return (f"LowCmd_.crc: expected 0x{expected_crc:08X} (CRC-32/MPEG-2 of the first "
                f"{_CRC_WORDS} words), received 0x{crc:08X}")
    return None


def sdk_command_from_low_cmd(record: np.ndarray) -> SdkMotorCommand:
    """The leg motors' command (slots 0 to 11) of a ``LowCmd_`` record the robot would take.

    Raises:
        FrameError: A wrong header or CRC (:func:`low_cmd_fault`), or motor values an
            :class:`SdkMotorCommand` rejects (a mode other than 0x00/0x01, a negative gain, a
            non-finite value, a stop sentinel under a gain), each named.
        ConfigurationError: ``record`` is not a ``LowCmd_`` record.
    """
    fault = low_cmd_fault(record)
    if fault is not None:
        raise FrameError(fault)
    motors = record["motor_cmd"][_LEGS]
    try:
        return SdkMotorCommand(mode=motors["mode"], q=motors["q"], dq=motors["dq"],
                               tau=motors["tau"], kp=motors["kp"], kd=motors["kd"])
    except ConfigurationError as err:
        raise FrameError(f"LowCmd_.motor_cmd[0..{SDK_LEG_MOTORS - 1}]: {err}") from err


def _hex_bytes(values: np.ndarray) -> str:
    return " ".join(f"{int(v):02X}" for v in values)
