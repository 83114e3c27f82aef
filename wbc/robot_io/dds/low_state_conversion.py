"""A ``LowState_`` C-image record (:data:`~wbc.robot_io.dds.c_layout.LOW_STATE_DTYPE`) as a
:class:`~wbc.robot_io.sensor_record.SensorRecord` and back, with array operations only.

The mapping is that of :func:`wbc.robot_io.sdk_low_state.sensor_record_from_message`: motor
slots 0 to 11 in the SDK's order (FR, FL, RR, RL) mapped by joint name through
:meth:`~wbc.model.joint_map.JointMap.unitree_sdk`, ``foot_force`` from the SDK's leg order to
the description's (FL, FR, RL, RR), ``stamp_s`` by default the ``tick`` read as milliseconds;
non-finite readings pass through to the estimator. Fields and units:
:mod:`wbc.robot_io.unitree_sdk`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.model.description import LEGS, UNITREE_SDK_LEGS
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS
from wbc.robot_io.dds.c_layout import (
    HEAD,
    LOW_STATE_DTYPE,
    MOTOR_STATE_DTYPE,
    check_record,
    set_crc,
    zero_record,
)
from wbc.robot_io.sensor_record import SensorRecord
from wbc.robot_io.unitree_sdk import SDK_LEG_MOTORS

_SDK = JointMap.unitree_sdk()
#: Each description leg's slot in the SDK's foot order.
_SDK_LEG_SLOTS = np.array([UNITREE_SDK_LEGS.index(leg) for leg in LEGS])
#: Each SDK leg's slot in the description's foot order.
_DESCRIPTION_LEG_SLOTS = np.array([LEGS.index(leg) for leg in UNITREE_SDK_LEGS])
_INT16 = np.iinfo(np.int16)


def _word_index(field: str, count: int, size: int) -> np.ndarray:
    """Where ``count`` consecutive ``size``-byte values from ``field`` (a path such as
    ``imu_state.gyroscope``) sit in a LowState_ image, in ``size``-byte words."""
    dtype, offset = LOW_STATE_DTYPE, 0
    for name in field.split("."):
        sub, at = dtype.fields[name][:2]
        offset += at
        dtype = sub.base if sub.subdtype is not None else sub
    assert offset % size == 0  # align=True: every field on its own size
    return offset // size + np.arange(count)


def _motor_words(field: str) -> np.ndarray:
    """The 12 leg motors' ``field`` as float32 words, in the description's joint order."""
    at = LOW_STATE_DTYPE.fields["motor_state"][1] + MOTOR_STATE_DTYPE.fields[field][1]
    sdk = (at + MOTOR_STATE_DTYPE.itemsize * np.arange(SDK_LEG_MOTORS)) // 4
    return sdk[_SDK.inverse]


#: The float32 words :func:`sensor_record_from_low_state` reads, in the order it writes them:
#: quaternion (4), gyroscope (3), accelerometer (3), then q, dq, tau_est (12 each).
_FLOAT_WORDS = np.concatenate([
    _word_index("imu_state.quaternion", 4, 4), _word_index("imu_state.gyroscope", 3, 4),
    _word_index("imu_state.accelerometer", 3, 4), _motor_words("q"), _motor_words("dq"),
    _motor_words("tau_est")]).astype(np.int64)
#: The int16 words of ``foot_force``, in the description's leg order.
_FOOT_HALVES = _word_index("foot_force", 4, 2)[_SDK_LEG_SLOTS].astype(np.int64)
_F8 = numba.float64[::1]


@numba.njit(numba.void(numba.uint8[::1], numba.int64[::1], numba.int64[::1], _F8, _F8, _F8,
                       _F8, _F8, _F8, _F8), cache=True)
def _gather(image, float_words, foot_halves, quaternion, gyroscope, accelerometer, q, dq,
            tau_est, foot_force):
    """The sensor values of a LowState_ image (its bytes) into the record's vectors."""
    words, halves = image.view(np.float32), image.view(np.int16)
    targets = (quaternion, gyroscope, accelerometer, q, dq, tau_est)
    size = 0
    for target in targets:
        size += target.shape[0]
    if size != float_words.shape[0] or foot_force.shape[0] != foot_halves.shape[0]:
        raise ValueError("a vector of the sensor record has another length")
    k = 0
    for target in targets:
        for i in range(target.shape[0]):
            target[i] = words[float_words[k]]
            k += 1
    for i in range(4):
        foot_force[i] = halves[foot_halves[i]]


def sensor_record_from_low_state(record: np.ndarray, *, stamp_s: float | None = None,
                                 out: SensorRecord | None = None) -> SensorRecord:
    """The sensor values of a ``LowState_`` record, in the description's orders.

    The CRC is not checked here (see :func:`~wbc.robot_io.dds.c_layout.crc_ok`).

    Args:
        record: A 0-d array of ``LOW_STATE_DTYPE``.
        stamp_s: When it was taken [s]; by default ``tick`` read as milliseconds.
        out: A record to overwrite in place (the control loop's, reused every tick); a new
            one when not given. Either way the record is tagged
            :data:`~wbc.model.orders.DESCRIPTION_ORDERS`.

    Raises:
        ConfigurationError: ``record`` is not a ``LowState_`` record.
    """
    check_record(record, LOW_STATE_DTYPE, "record")
    imu = record["imu_state"]
    motors = record["motor_state"][:SDK_LEG_MOTORS]
    joints = _SDK.inverse  # description[j] = sdk[inverse[j]]
    tick = int(record["tick"])
    stamp = tick * 1e-3 if stamp_s is None else stamp_s
    if out is None:
        return SensorRecord(
            stamp_s=stamp, tick=tick, imu_quaternion_wxyz=imu["quaternion"],
            gyroscope_rad_s=imu["gyroscope"], accelerometer_m_s2=imu["accelerometer"],
            q=motors["q"][joints], dq=motors["dq"][joints], tau_est=motors["tau_est"][joints],
            foot_force=record["foot_force"][_SDK_LEG_SLOTS], orders=DESCRIPTION_ORDERS)
    out.orders = DESCRIPTION_ORDERS  # whatever the buffer held before: these orders now
    out.stamp_s = float(stamp)
    out.tick = tick
    try:  # the buffers SensorRecord.zeros makes (float64 vectors): one compiled call
        _gather(np.frombuffer(record, dtype=np.uint8), _FLOAT_WORDS, _FOOT_HALVES,
                out.imu_quaternion_wxyz, out.gyroscope_rad_s, out.accelerometer_m_s2, out.q,
                out.dq, out.tau_est, out.foot_force)
        return out
    except (TypeError, ValueError):  # other arrays: NumPy's assignments convert or name them
        pass
    out.imu_quaternion_wxyz[:] = imu["quaternion"]
    out.gyroscope_rad_s[:] = imu["gyroscope"]
    out.accelerometer_m_s2[:] = imu["accelerometer"]
    out.q[:] = motors["q"][joints]
    out.dq[:] = motors["dq"][joints]
    out.tau_est[:] = motors["tau_est"][joints]
    out.foot_force[:] = record["foot_force"][_SDK_LEG_SLOTS]
    return out


def rpy_from_wxyz(quaternion: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw [rad] (ZYX angles, as ``IMUState_.rpy``) of a ``(w, x, y, z)``
    quaternion, normalised first; NaN for a zero or non-finite quaternion."""
    w, x, y, z = (float(v) for v in quaternion)  # scalar math: ~10x faster than NumPy's
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    if not (math.isfinite(norm) and norm > 0.0):
        return (math.nan, math.nan, math.nan)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    return (math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
            math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x)))),
            math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z)))


def low_state_from_sensor_record(sensor: SensorRecord, *,
                                 out: np.ndarray | None = None) -> np.ndarray:
    """The ``LowState_`` record a robot with these sensor values sends (a simulator bridge).

    Sets ``head`` (FE EF), ``imu_state`` (quaternion, gyroscope, accelerometer, and ``rpy``
    from the quaternion), ``motor_state[0..11]`` ``q``, ``dq``, ``tau_est`` in the SDK's
    order, ``foot_force`` in the SDK's leg order, ``tick`` and the CRC. ``foot_force`` is
    int16 in the message: rounded, clipped to its range, NaN sent as 0. ``tick`` wraps at
    2^32 like the robot's counter. Everything else is left as it is in ``out`` (zeros in a
    new record).

    Args:
        sensor: The values, in the description's orders (checked: ``sensor.orders``).
        out: A record to fill in place; a new one when not given.

    Raises:
        OrderMismatchError: ``sensor`` is in other orders (a plant's own), named with the
            description's.
        ConfigurationError: ``out`` is not a ``LowState_`` record.
    """
    if sensor.orders is not DESCRIPTION_ORDERS:
        sensor.orders.check(DESCRIPTION_ORDERS, what="low_state_from_sensor_record(sensor)",
                            fix="map the plant's record to the description's orders by name "
                                "first (this conversion maps that to the SDK's)")
    if out is None:
        out = zero_record(LOW_STATE_DTYPE)
    else:
        check_record(out, LOW_STATE_DTYPE, "out")
    out["head"] = HEAD
    imu = out["imu_state"]
    imu["quaternion"] = sensor.imu_quaternion_wxyz
    imu["gyroscope"] = sensor.gyroscope_rad_s
    imu["accelerometer"] = sensor.accelerometer_m_s2
    imu["rpy"] = rpy_from_wxyz(sensor.imu_quaternion_wxyz)
    motors = out["motor_state"]
    joints = _SDK.index  # sdk[k] = description[index[k]]
    motors["q"][:SDK_LEG_MOTORS] = sensor.q[joints]
    motors["dq"][:SDK_LEG_MOTORS] = sensor.dq[joints]
    motors["tau_est"][:SDK_LEG_MOTORS] = sensor.tau_est[joints]
    feet = sensor.foot_force[_DESCRIPTION_LEG_SLOTS]  # a copy
    feet[np.isnan(feet)] = 0.0
    np.rint(feet, out=feet)
    out["foot_force"] = np.minimum(np.maximum(feet, _INT16.min), _INT16.max)
    out["tick"] = sensor.tick % (1 << 32)
    set_crc(out)
    return out
