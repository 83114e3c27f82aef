"""The reused ``LowCmd_`` of a control loop, filled in one compiled call: :class:`LowCmdFrame`.

The checked way to a record, :meth:`SdkMotorCommand.from_control_output
<wbc.robot_io.sdk_motor_command.SdkMotorCommand.from_control_output>` then
:func:`~wbc.robot_io.dds.low_cmd_conversion.low_cmd_from_sdk_command`, validates with NumPy
and builds objects for every message (~45 us here); it stays the way for user input and for
the reasons it names. A control loop sends a command the controller's guard has already
checked, 500 to 1000 times a second, into the same record: :meth:`LowCmdFrame.fill` writes the
12 leg slots (reordered by joint name, the stop sentinels where a gain is zero), ``reserve``
and the CRC in one compiled pass (~2 us), with the same bytes as the checked path. The checks
that path makes (12 finite values per field, gains >= 0, no stop sentinel under a gain) are
made too, compiled and before anything is written: a command that fails them leaves the record
as it was and :meth:`~LowCmdFrame.fill` returns ``False`` (the caller then asks the checked
path what is wrong).

The header (``head``, ``level_flag``), every motor's ``mode`` (0x01) and the idle slots 12 to 19
are written once, when the frame is made, as
:func:`~wbc.robot_io.dds.c_layout.sdk_default_low_cmd` writes them; nothing here changes them.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS
from wbc.robot_io.dds.c_layout import (
    LOW_CMD_DTYPE,
    MOTOR_CMD_DTYPE,
    _crc32_words,
    sdk_default_low_cmd,
)
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_motor_command import FROM_DESCRIPTION_ONLY
from wbc.robot_io.unitree_sdk import POS_STOP_F, SDK_LEG_MOTORS, VEL_STOP_F

# Messages carry float32: a sentinel within this relative distance is one (as
# SdkMotorCommand recognises them).
_SENTINEL_RTOL = 1e-6


def _word(offset: int) -> int:
    """A byte offset of the C image as a 32-bit word index (every field used is aligned)."""
    if offset % 4:
        raise AssertionError(f"offset {offset} is not on a 32-bit word")  # a layout change
    return offset // 4


#: Word of ``motor_cmd[0]``; words from one motor to the next; each field's word in a motor.
_FIRST = _word(LOW_CMD_DTYPE.fields["motor_cmd"][1])
_STRIDE = _word(MOTOR_CMD_DTYPE.itemsize)
_Q, _DQ, _TAU, _KP, _KD = (_word(MOTOR_CMD_DTYPE.fields[name][1])
                           for name in ("q", "dq", "tau", "kp", "kd"))
_RESERVE = _word(LOW_CMD_DTYPE.fields["reserve"][1])
_CRC = _word(LOW_CMD_DTYPE.fields["crc"][1])

_VECTOR = numba.float64[:]


@numba.njit(numba.boolean(_VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR, numba.intp[::1],
                          numba.boolean, numba.uint32, numba.float32[::1], numba.uint32[::1]),
            cache=True)
def _fill(q_des, dq_des, kp, kd, tau_ff, index, stop_sentinels, reserve, floats,
          words):  # pragma: no cover - compiled
    """Write the leg slots ``k`` from ``command[index[k]]``, ``reserve`` and the CRC into the
    record seen as ``floats`` / ``words``; ``False``, writing nothing, when a value fails the
    checked path's checks."""
    n = index.shape[0]
    if (q_des.shape[0] != n or dq_des.shape[0] != n or kp.shape[0] != n or kd.shape[0] != n
            or tau_ff.shape[0] != n):
        return False
    q_stop, dq_stop = _SENTINEL_RTOL * POS_STOP_F, _SENTINEL_RTOL * VEL_STOP_F
    for k in range(n):
        i = index[k]
        p, d, q, dq = kp[i], kd[i], q_des[i], dq_des[i]
        if not (math.isfinite(q) and math.isfinite(dq) and math.isfinite(tau_ff[i])
                and math.isfinite(p) and math.isfinite(d) and p >= 0.0 and d >= 0.0):
            return False
        if stop_sentinels and p == 0.0:
            q = POS_STOP_F
        if stop_sentinels and d == 0.0:
            dq = VEL_STOP_F
        # A sentinel is a target 2e9 rad away: refused where a gain multiplies it.
        if (p > 0.0 and abs(q - POS_STOP_F) <= q_stop) or (
                d > 0.0 and abs(dq - VEL_STOP_F) <= dq_stop):
            return False
    for k in range(n):
        i = index[k]
        base = _FIRST + k * _STRIDE
        p, d = kp[i], kd[i]
        floats[base + _Q] = POS_STOP_F if stop_sentinels and p == 0.0 else q_des[i]
        floats[base + _DQ] = VEL_STOP_F if stop_sentinels and d == 0.0 else dq_des[i]
        floats[base + _TAU] = tau_ff[i]
        floats[base + _KP] = p
        floats[base + _KD] = d
    words[_RESERVE] = reserve
    words[_CRC] = _crc32_words(words, _CRC)
    return True


class LowCmdFrame:
    """A ``LowCmd_`` record (:attr:`record`) a control loop refills and publishes every tick.

    Made as the SDK's default command (:func:`~wbc.robot_io.dds.c_layout.sdk_default_low_cmd`:
    the header, every motor enabled, the idle slots); :meth:`fill` then writes the legs,
    ``reserve`` and the CRC. Writing the record another way (the checked path, into
    :attr:`record`) is fine: it writes the same header, modes and idle slots.

    Args:
        use_stop_sentinels: Write :data:`~wbc.robot_io.unitree_sdk.POS_STOP_F` as ``q`` where
            ``kp = 0`` and :data:`~wbc.robot_io.unitree_sdk.VEL_STOP_F` as ``dq`` where
            ``kd = 0``, as ``SdkMotorCommand.from_control_output`` does by default.

    Example:
        >>> frame = LowCmdFrame()
        >>> message = LowCmdMessage(frame.record)
        >>> if frame.fill(controller_output, reserve=state_tick):
        ...     writer.write(message)
    """

    def __init__(self, *, use_stop_sentinels: bool = True) -> None:
        #: The record (a 0-d array of ``LOW_CMD_DTYPE``), refilled in place.
        self.record = sdk_default_low_cmd()
        self.use_stop_sentinels = bool(use_stop_sentinels)
        self._floats = np.frombuffer(self.record, dtype=np.float32)
        self._words = np.frombuffer(self.record, dtype=np.uint32)
        # sdk[k] = description[index[k]], by joint name
        self._index = np.ascontiguousarray(JointMap.unitree_sdk().index, dtype=np.intp)
        if len(self._index) != SDK_LEG_MOTORS:
            raise AssertionError("the SDK joint map does not have 12 joints")

    def fill(self, command: MotorCommand, *, reserve: int = 0) -> bool:
        """Write ``command`` (description order) into the leg slots, ``reserve`` and the CRC.

        Returns:
            ``True`` when written; ``False`` when a value fails the checks of the checked path
            (a wrong shape, a non-finite value, a negative gain, a stop sentinel under a
            gain) or an array is not float64: the record is then unchanged, and
            ``SdkMotorCommand.from_control_output(command)`` says what is wrong (or, for
            another dtype, converts it).

        Raises:
            OrderMismatchError: ``command`` is in another joint order (``command.orders``),
                named with the description's; nothing is written.
        """
        orders = command.orders
        if orders is not DESCRIPTION_ORDERS:
            orders.check(DESCRIPTION_ORDERS, what="LowCmdFrame.fill(command)", legs=False,
                         fix=FROM_DESCRIPTION_ONLY)
        try:
            return _fill(command.q_des, command.dq_des, command.kp, command.kd,
                         command.tau_ff, self._index, self.use_stop_sentinels,
                         reserve & 0xFFFFFFFF, self._floats, self._words)
        except TypeError:  # not float64 vectors: the checked path converts or names them
            return False
