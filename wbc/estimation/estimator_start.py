"""What an estimator needs to start from a sample, and the attitude gravity gives at rest."""

from __future__ import annotations

import numpy as np

from wbc.model.description import JOINT_NAMES
from wbc.robot_io.sensor_record import SensorRecord

#: Gravity [m/s^2] an accelerometer at rest reads.
GRAVITY_M_S2 = 9.81


def start_problem(record: SensorRecord | None, *, quaternion_tolerance: float,
                  needs_quaternion: bool) -> str:
    """Why ``record`` cannot start an estimator ('' when it can), the field named.

    A start needs finite joint angles and velocities, a finite gyroscope, and the attitude:
    a unit IMU quaternion (within ``quaternion_tolerance`` of norm 1) or, for an estimator
    that does not need one (``needs_quaternion`` false), an accelerometer reading gravity
    (within half of it), from which :func:`level_quaternion` takes roll and pitch.
    """
    if record is None:
        return "no sensor sample"
    if not isinstance(record, SensorRecord):
        return f"record: expected a SensorRecord, received {type(record).__name__}"
    for name in ("q", "dq"):
        values = np.asarray(getattr(record, name), dtype=float)
        if not np.isfinite(values).all():
            bad = [JOINT_NAMES[j] for j in np.flatnonzero(~np.isfinite(values))]
            return f"{name}: non-finite reading at {', '.join(bad)}"
    gyro = np.asarray(record.gyroscope_rad_s, dtype=float)
    if not np.isfinite(gyro).all():
        return f"gyroscope_rad_s: non-finite reading {gyro.tolist()}"
    quat = np.asarray(record.imu_quaternion_wxyz, dtype=float)
    norm = float(np.linalg.norm(quat))
    if abs(norm - 1.0) <= quaternion_tolerance:
        return ""
    why = (f"imu_quaternion_wxyz: expected a unit quaternion (w, x, y, z), received "
           f"{quat.tolist()} (norm {norm:g})")
    if needs_quaternion:
        return why
    accel = np.asarray(record.accelerometer_m_s2, dtype=float)
    gravity = float(np.linalg.norm(accel))
    if not np.isfinite(accel).all() or not 0.5 * GRAVITY_M_S2 < gravity < 1.5 * GRAVITY_M_S2:
        return (f"{why}, and accelerometer_m_s2: expected gravity's {GRAVITY_M_S2:g} m/s^2 at "
                f"rest to take roll and pitch from, received {accel.tolist()}")
    return ""


def start_attitude(record: SensorRecord, quaternion_tolerance: float) -> tuple[np.ndarray, str]:
    """The attitude (w, x, y, z) to start from and a note ('' when none): the IMU's unit
    quaternion, or without one (not within ``quaternion_tolerance`` of norm 1), roll and
    pitch from the accelerometer (:func:`level_quaternion`) and yaw 0."""
    quat = np.asarray(record.imu_quaternion_wxyz, dtype=float)
    if abs(float(np.linalg.norm(quat)) - 1.0) <= quaternion_tolerance:  # False for NaN
        return quat, ""
    return (level_quaternion(np.asarray(record.accelerometer_m_s2, dtype=float)),
            "started without the IMU quaternion: roll and pitch from the accelerometer, yaw 0")


#: Feet this close [m] to the lowest one stand on the floor at a start; higher ones are in the
#: air (a leg left raised when the state was lost).
FLOOR_BAND_M = 0.05


def floor_shift(feet_z: np.ndarray, radius_m: float) -> float:
    """How much [m] to raise a start whose four foot centres ``feet_z`` [m] average one foot
    radius ``radius_m`` [m] above the floor, so that those standing on it (within
    :data:`FLOOR_BAND_M` of the lowest) do instead: a foot left in the air (a high five's,
    when the state was lost) does not lower the whole estimate by a quarter of its height."""
    on_floor = feet_z <= feet_z.min() + FLOOR_BAND_M
    return float(radius_m - feet_z[on_floor].mean())


def level_quaternion(accel: np.ndarray) -> np.ndarray:
    """The attitude (w, x, y, z), yaw 0, whose gravity the accelerometer ``accel`` [m/s^2]
    reads at rest: it measures the specific force, ``R^T (0, 0, g)`` in the body frame."""
    ax, ay, az = accel / np.linalg.norm(accel)
    roll = np.arctan2(ay, az)
    pitch = np.arctan2(-ax, np.hypot(ay, az))
    cr, sr, cp, sp = np.cos(roll / 2), np.sin(roll / 2), np.cos(pitch / 2), np.sin(pitch / 2)
    return np.array([cr * cp, sr * cp, cr * sp, -sr * sp])  # R = Ry(pitch) Rx(roll)
