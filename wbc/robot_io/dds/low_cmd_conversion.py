"""An :class:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand` as a ``LowCmd_`` C-image record
(:data:`~wbc.robot_io.dds.c_layout.LOW_CMD_DTYPE`) and back, with the checks the robot makes.

Out: the SDK's header (FE EF / 0xFF), motor slots 0 to 11 carry the command, slots 12 to 19
the SDK's idle command (:func:`~wbc.robot_io.unitree_sdk.set_idle_motor_slots`, the convention
of :meth:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand.write_to` too), the CRC is set. In:
a record is used only with the SDK's header and a matching CRC, as the robot drops any other;
:func:`low_cmd_fault` names what is wrong without raising. :func:`motor_command_from_low_cmd` is
the receiving side's fast path: the same checks and conversion, compiled (~3 us, where the
checked path takes ~60 us), for a robot or simulator taking every command.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.model.orders import UNITREE_SDK_ORDERS
from wbc.robot_io.dds.c_layout import (
    _WORDS,
    HEAD,
    LEVEL_FLAG_LOW,
    LOW_CMD_DTYPE,
    MOTOR_CMD_DTYPE,
    _crc32_words,
    check_record,
    low_cmd_crc,
    sdk_default_low_cmd,
)
from wbc.robot_io.dds.cdr_codec import FrameError
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.unitree_sdk import (
    MODE_ENABLE,
    MODE_STOP,
    POS_STOP_F,
    SDK_LEG_MOTORS,
    VEL_STOP_F,
    set_idle_motor_slots,
)

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


# The C image as bytes / float32 / uint32 (every field used is aligned to its size).
_MOTOR0 = LOW_CMD_DTYPE.fields["motor_cmd"][1]
_MOTOR_SIZE = MOTOR_CMD_DTYPE.itemsize
_MODE, _Q, _DQ, _TAU, _KP, _KD = (MOTOR_CMD_DTYPE.fields[name][1]
                                  for name in ("mode", "q", "dq", "tau", "kp", "kd"))
_HEAD0, _LEVEL_FLAG = LOW_CMD_DTYPE.fields["head"][1], LOW_CMD_DTYPE.fields["level_flag"][1]
_SENTINEL_RTOL = 1e-6  # as SdkMotorCommand recognises a sentinel that went through float32
_BYTES = numba.types.Array(numba.uint8, 1, "C", readonly=True)
_FLOATS = numba.types.Array(numba.float32, 1, "C", readonly=True)
_OUT = numba.float64[::1]


@numba.njit(numba.boolean(_BYTES, _FLOATS, _WORDS, numba.intp[::1], _OUT, _OUT, _OUT, _OUT,
                          _OUT, _OUT), cache=True)
def _driver_command(raw, floats, words, slots, effort_limit, q_des, dq_des, kp_out, kd_out,
                    tau_ff):  # pragma: no cover - compiled
    """The checks and conversion of the checked path (see :func:`motor_command_from_low_cmd`);
    ``False`` as soon as one fails."""
    if (raw[_HEAD0] != HEAD[0] or raw[_HEAD0 + 1] != HEAD[1]
            or raw[_LEVEL_FLAG] != LEVEL_FLAG_LOW):
        return False
    crc_word = words.shape[0] - 1
    if _crc32_words(words, crc_word) != words[crc_word]:
        return False
    q_stop, dq_stop = _SENTINEL_RTOL * POS_STOP_F, _SENTINEL_RTOL * VEL_STOP_F
    for k in range(SDK_LEG_MOTORS):  # every leg slot is checked, whichever are used
        base = _MOTOR0 + k * _MOTOR_SIZE
        mode = raw[base + _MODE]
        q, dq, tau = np.float64(floats[(base + _Q) // 4]), np.float64(
            floats[(base + _DQ) // 4]), np.float64(floats[(base + _TAU) // 4])
        kp, kd = np.float64(floats[(base + _KP) // 4]), np.float64(floats[(base + _KD) // 4])
        if mode != MODE_STOP and mode != MODE_ENABLE:
            return False
        if not (math.isfinite(q) and math.isfinite(dq) and math.isfinite(tau)
                and math.isfinite(kp) and math.isfinite(kd) and kp >= 0.0 and kd >= 0.0):
            return False
        if (kp > 0.0 and abs(q - POS_STOP_F) <= q_stop) or (
                kd > 0.0 and abs(dq - VEL_STOP_F) <= dq_stop):
            return False
    for j in range(slots.shape[0]):
        base = _MOTOR0 + slots[j] * _MOTOR_SIZE
        enabled = raw[base + _MODE] == MODE_ENABLE
        q, dq = np.float64(floats[(base + _Q) // 4]), np.float64(floats[(base + _DQ) // 4])
        q_des[j] = q if enabled and not abs(q - POS_STOP_F) <= q_stop else 0.0
        dq_des[j] = dq if enabled and not abs(dq - VEL_STOP_F) <= dq_stop else 0.0
        kp_out[j] = np.float64(floats[(base + _KP) // 4]) if enabled else 0.0
        kd_out[j] = np.float64(floats[(base + _KD) // 4]) if enabled else 0.0
        tau_ff[j] = np.float64(floats[(base + _TAU) // 4]) if enabled else 0.0
        if not abs(tau_ff[j]) <= effort_limit[j]:
            return False
    return True


def motor_command_from_low_cmd(record: np.ndarray, *, slots: np.ndarray,
                               effort_limit: np.ndarray) -> MotorCommand | None:
    """What the motor drivers apply from a ``LowCmd_`` record, or ``None`` when they would
    refuse it: the compiled twin of the checked path.

    The checked path: :func:`low_cmd_fault` (``head``, ``level_flag``, CRC), then
    :func:`sdk_command_from_low_cmd` (every leg slot: mode 0x00 or 0x01, finite values,
    gains >= 0, no stop sentinel under a gain), :meth:`SdkMotorCommand.to_motor_command`
    (a stopped motor all zeros, a sentinel target 0), reordered, then
    :meth:`MotorCommand.problems` against ``effort_limit``. The result is equal to it, value
    for value; on ``None``, that path names the reason.

    Args:
        record: A ``LowCmd_`` record (e.g. a received sample's; read-only is fine).
        slots: For each joint of the result, its SDK motor slot (0 to 11), ``intp``; the
            result's ``orders`` are the SDK's joints taken at ``slots``.
        effort_limit: Each joint's effort limit [N m] (float64, the result's order).

    Raises:
        ConfigurationError: ``record`` is not a ``LowCmd_`` record.
    """
    check_record(record, LOW_CMD_DTYPE, "record")
    n = len(slots)
    out = [np.empty(n) for _ in range(5)]
    if not _driver_command(np.frombuffer(record, dtype=np.uint8),
                           np.frombuffer(record, dtype=np.float32),
                           np.frombuffer(record, dtype=np.uint32), slots, effort_limit, *out):
        return None
    q_des, dq_des, kp, kd, tau_ff = out
    return MotorCommand(q_des=q_des, dq_des=dq_des, kp=kp, kd=kd, tau_ff=tau_ff,
                        orders=UNITREE_SDK_ORDERS.reordered(slots))


def _hex_bytes(values: np.ndarray) -> str:
    return " ".join(f"{int(v):02X}" for v in values)
