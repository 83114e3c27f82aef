"""The C memory image of ``LowCmd_`` and ``LowState_`` as NumPy records, and their CRC.

The robot checks every command against a CRC computed over the message as the C++ SDK lays it
out in memory (natural alignment, with padding), not over the bytes on the wire. The records
here are that image: a 0-d NumPy array of :data:`LOW_CMD_DTYPE` (812 B) or
:data:`LOW_STATE_DTYPE` (1180 B), fields named as in :mod:`wbc.robot_io.dds.go2_types`::

    cmd = sdk_default_low_cmd()
    cmd["motor_cmd"]["q"][:12] = q_sdk       # (20,) float32 views
    set_crc(cmd)

CRC: CRC-32/MPEG-2 (polynomial 0x04C11DB7, init 0xFFFFFFFF, no reflection, no final XOR) over
the image read as little-endian 32-bit words, each fed most significant bit first, excluding
the final ``crc`` word (202 words of a command, 294 of a state). Padding bytes count: records
made here keep them zero, as the SDK's zero-initialised messages do.
"""

from __future__ import annotations

import numba
import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.robot_io.unitree_sdk import SDK_MOTOR_SLOTS, set_idle_motor_slots

_U1, _U2, _U4, _I2, _I4, _F4 = "u1", "<u2", "<u4", "<i2", "<i4", "<f4"

#: ``MotorCmd_`` (36 B).
MOTOR_CMD_DTYPE = np.dtype([
    ("mode", _U1), ("q", _F4), ("dq", _F4), ("tau", _F4), ("kp", _F4), ("kd", _F4),
    ("reserve", _U4, 3),
], align=True)
#: ``BmsCmd_`` (4 B).
BMS_CMD_DTYPE = np.dtype([("off", _U1), ("reserve", _U1, 3)], align=True)
#: ``LowCmd_`` (812 B): what ``rt/lowcmd`` carries, as the C++ SDK holds it in memory.
LOW_CMD_DTYPE = np.dtype([
    ("head", _U1, 2), ("level_flag", _U1), ("frame_reserve", _U1), ("sn", _U4, 2),
    ("version", _U4, 2), ("bandwidth", _U2), ("motor_cmd", MOTOR_CMD_DTYPE, SDK_MOTOR_SLOTS),
    ("bms_cmd", BMS_CMD_DTYPE), ("wireless_remote", _U1, 40), ("led", _U1, 12),
    ("fan", _U1, 2), ("gpio", _U1), ("reserve", _U4), ("crc", _U4),
], align=True)
#: ``IMUState_`` (56 B).
IMU_STATE_DTYPE = np.dtype([
    ("quaternion", _F4, 4), ("gyroscope", _F4, 3), ("accelerometer", _F4, 3), ("rpy", _F4, 3),
    ("temperature", _U1),
], align=True)
#: ``MotorState_`` (48 B).
MOTOR_STATE_DTYPE = np.dtype([
    ("mode", _U1), ("q", _F4), ("dq", _F4), ("ddq", _F4), ("tau_est", _F4), ("q_raw", _F4),
    ("dq_raw", _F4), ("ddq_raw", _F4), ("temperature", _U1), ("lost", _U4), ("reserve", _U4, 2),
], align=True)
#: ``BmsState_`` (44 B).
BMS_STATE_DTYPE = np.dtype([
    ("version_high", _U1), ("version_low", _U1), ("status", _U1), ("soc", _U1),
    ("current", _I4), ("cycle", _U2), ("bq_ntc", _U1, 2), ("mcu_ntc", _U1, 2),
    ("cell_vol", _U2, 15),
], align=True)
#: ``LowState_`` (1180 B): what ``rt/lowstate`` carries, as the C++ SDK holds it in memory.
LOW_STATE_DTYPE = np.dtype([
    ("head", _U1, 2), ("level_flag", _U1), ("frame_reserve", _U1), ("sn", _U4, 2),
    ("version", _U4, 2), ("bandwidth", _U2), ("imu_state", IMU_STATE_DTYPE),
    ("motor_state", MOTOR_STATE_DTYPE, SDK_MOTOR_SLOTS), ("bms_state", BMS_STATE_DTYPE),
    ("foot_force", _I2, 4), ("foot_force_est", _I2, 4), ("tick", _U4),
    ("wireless_remote", _U1, 40), ("bit_flag", _U1), ("adc_reel", _F4),
    ("temperature_ntc1", _U1), ("temperature_ntc2", _U1), ("power_v", _F4), ("power_a", _F4),
    ("fan_frequency", _U2, 4), ("reserve", _U4), ("crc", _U4),
], align=True)

#: ``head`` of every message the SDK sends.
HEAD = (0xFE, 0xEF)
#: ``level_flag`` of a low-level command (the SDK's ``LOWLEVEL``).
LEVEL_FLAG_LOW = 0xFF

_POLYNOMIAL = 0x04C11DB7


def _crc_tables() -> np.ndarray:
    """Slicing-by-4 tables: ``tables[k][b]`` is the CRC register after feeding byte ``b``
    followed by ``k`` zero bytes into a zero register (MSB first)."""
    tables = np.zeros((4, 256), dtype=np.uint32)
    for byte in range(256):
        reg = byte << 24
        for _ in range(8):
            reg = ((reg << 1) ^ _POLYNOMIAL if reg & 0x80000000 else reg << 1) & 0xFFFFFFFF
        tables[0, byte] = reg
    for k in range(1, 4):
        previous = tables[k - 1].astype(np.uint64)
        tables[k] = ((previous << 8) & 0xFFFFFFFF) ^ tables[0][previous >> 24]
    return tables


_TABLES = _crc_tables()


# Read-only words: a writable array converts to it, and records viewed from received bytes are
# read-only.
_WORDS = numba.types.Array(numba.uint32, 1, "C", readonly=True)


@numba.njit(numba.uint32(_WORDS, numba.intp), cache=True)
def _crc32_words(words, count):  # pragma: no cover - compiled
    """CRC-32/MPEG-2 of ``words[:count]`` (``count <= len(words)``: not bounds-checked), each
    word fed most significant bit first.

    One word is four table look-ups (slicing by 4): ~1 us for a whole ``LowState_`` where
    the SDK's bit loop in Python takes ~0.8 ms.
    """
    tables = _TABLES
    crc = np.uint32(0xFFFFFFFF)
    for i in range(count):
        x = crc ^ words[i]
        crc = np.uint32(tables[3, x >> 24] ^ tables[2, (x >> 16) & 0xFF]
                        ^ tables[1, (x >> 8) & 0xFF] ^ tables[0, x & 0xFF])
    return crc


def crc32_bit_by_bit(words: np.ndarray) -> int:
    """CRC-32/MPEG-2 of ``words`` (uint32) as the SDK's C loop computes it: each word fed most
    significant bit first, one bit at a time. The slow reference (~0.8 ms for a
    ``LowState_``) that the compiled tables are checked and timed against."""
    crc = 0xFFFFFFFF
    for word in np.asarray(words, dtype=np.uint32).tolist():
        for bit in range(31, -1, -1):
            top = crc >> 31
            crc = (crc << 1) & 0xFFFFFFFF
            if top ^ ((word >> bit) & 1):
                crc ^= _POLYNOMIAL
    return crc


def zero_record(dtype: np.dtype) -> np.ndarray:
    """A zeroed 0-d record of ``dtype`` (e.g. :data:`LOW_STATE_DTYPE`).

    Built on a ``bytearray``: ~0.2 us where ``np.zeros((), dtype)`` takes ~3 us for these
    structured dtypes.
    """
    return np.ndarray((), dtype=dtype, buffer=bytearray(dtype.itemsize))


def check_record(record: object, dtype: np.dtype, name: str) -> None:
    """Raise unless ``record`` is a 0-d NumPy array of ``dtype``.

    Raises:
        ConfigurationError: Naming ``name``, the expected layout and what was received.
    """
    if isinstance(record, np.ndarray) and record.shape == () and (
            record.dtype is dtype or record.dtype == dtype):
        return
    described = (f"an array of dtype {record.dtype} and shape {record.shape}"
                 if isinstance(record, np.ndarray) else type(record).__name__)
    kind = {LOW_CMD_DTYPE: "LowCmd_", LOW_STATE_DTYPE: "LowState_"}.get(dtype, str(dtype))
    raise ConfigurationError(
        f"{name}: expected a 0-d NumPy array of the {kind} C layout ({dtype.itemsize} B, "
        f"wbc.robot_io.dds.c_layout), received {described}")


def _words(record: np.ndarray, dtype: np.dtype, name: str) -> np.ndarray:
    """The record's memory as little-endian 32-bit words (a view)."""
    check_record(record, dtype, name)
    return np.frombuffer(record, dtype=np.uint32)


def low_cmd_crc(record: np.ndarray) -> int:
    """The CRC a ``LowCmd_`` record should carry (its ``crc`` field is not read).

    Raises:
        ConfigurationError: ``record`` is not a 0-d array of :data:`LOW_CMD_DTYPE`.
    """
    words = _words(record, LOW_CMD_DTYPE, "LowCmd_")
    return int(_crc32_words(words, len(words) - 1))


def low_state_crc(record: np.ndarray) -> int:
    """The CRC a ``LowState_`` record should carry (its ``crc`` field is not read).

    Raises:
        ConfigurationError: ``record`` is not a 0-d array of :data:`LOW_STATE_DTYPE`.
    """
    words = _words(record, LOW_STATE_DTYPE, "LowState_")
    return int(_crc32_words(words, len(words) - 1))


def _crc_of(record: np.ndarray) -> int:
    if isinstance(record, np.ndarray) and record.dtype == LOW_STATE_DTYPE:
        return low_state_crc(record)
    return low_cmd_crc(record)


def set_crc(record: np.ndarray) -> int:
    """Compute the CRC of a ``LowCmd_`` or ``LowState_`` record and store it in ``crc``.

    Returns:
        The CRC.

    Raises:
        ConfigurationError: ``record`` is neither record type.
    """
    crc = _crc_of(record)
    record["crc"] = crc
    return crc


def crc_ok(record: np.ndarray) -> bool:
    """Whether the ``crc`` field of a ``LowCmd_`` or ``LowState_`` record matches its content.

    Raises:
        ConfigurationError: ``record`` is neither record type.
    """
    return _crc_of(record) == int(record["crc"])


def sdk_default_low_cmd() -> np.ndarray:
    """A fresh ``LowCmd_`` record as the SDK's examples start one, with its CRC.

    ``head = FE EF``, ``level_flag = 0xFF``, every one of the 20 motors idle
    (:func:`~wbc.robot_io.unitree_sdk.set_idle_motor_slots`: ``mode = 0x01``,
    ``q = PosStopF`` (2.146e9), ``dq = VelStopF`` (16000.0), ``kp = kd = tau = 0``);
    everything else zero. Its CRC is 0x06E577CD.
    """
    record = zero_record(LOW_CMD_DTYPE)
    record["head"] = HEAD
    record["level_flag"] = LEVEL_FLAG_LOW
    set_idle_motor_slots(record["motor_cmd"], slice(None))
    set_crc(record)
    return record
