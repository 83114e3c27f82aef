"""What an estimator gives the controller each tick: the estimate, its fault flags, their words.

Every estimator here (:class:`wbc.LinearKalmanFilter`, :class:`wbc.InvariantEkf`) fills the same
:class:`StateEstimate` and raises the same flags, so the control loop, the run's log and the
tests read either the same way.
"""

from __future__ import annotations

import math

import numpy as np

from wbc.model.description import LEGS
from wbc.robot_io.sensor_record import SensorRecord

# Fault flags of one tick (every estimator's compiled tick returns them).
STALE, NO_DATA, QUATERNION_NON_FINITE, QUATERNION_NOT_UNIT = 1, 2, 4, 8
GYRO_BAD, ACCEL_BAD, JOINTS_BAD, FOOT_SENSOR = 16, 32, 64, 128
QUATERNION_TIMEOUT = 256
#: The feet's calibrated forces contradict the robot's weight: contact from the schedule.
FOOT_WEIGHT = 512
#: Flags that make a sample untrustworthy (the others are worked around).
UNTRUSTED = STALE | NO_DATA | GYRO_BAD | JOINTS_BAD | QUATERNION_TIMEOUT
# Why a foot sensor is distrusted.
FOOT_OK, FOOT_STUCK, FOOT_SATURATED, FOOT_NON_FINITE = 0, 1, 2, 3
#: The flags carry each foot's reason, two bits a foot (``LEGS`` order), from this bit on.
FOOT_REASON_SHIFT = 16
_FOOT_REASONS = {FOOT_STUCK: "stuck at {value:g}", FOOT_SATURATED: "at full scale ({value:g})",
                 FOOT_NON_FINITE: "non-finite ({value})"}


class StateEstimate:
    """What the estimator gives the controller, and what it thinks of it.

    Attributes:
        q: Configuration (19,), Pinocchio convention, description order (updated in place
            every tick: copy it to keep it).
        v: Velocity (18,): base linear and angular velocity in the base frame, joints.
        contact: Each foot's contact weight in ``LEGS`` order (4,): 1 a loaded stance foot,
            0 a foot the filter lets go.
        trusted: This tick's sample was fresh and complete (joints and gyroscope).
        untrusted_s: Time [s] since the last trustworthy sample.
        usable: ``untrusted_s`` is within the estimator's ``trust_timeout_s``.
        flags: The tick's fault flags (the module's constants).
        faults: What the estimator distrusts, in words ('' when nothing).
    """

    def __init__(self) -> None:
        self.q = np.zeros(19)
        self.q[6] = 1.0
        self.v = np.zeros(18)
        self.contact = np.ones(len(LEGS))
        self.trusted = True
        self.untrusted_s = 0.0
        self.usable = True
        self.flags = 0
        self.faults = ""


def describe_faults(flags: int, record: SensorRecord, foot_reason: np.ndarray,
                    quaternion_tolerance: float, quaternion_timeout_s: float,
                    quaternion_note: str = "orientation from the gyroscope",
                    weight_evidence: tuple[float, float] = (math.nan, math.nan)) -> str:
    """A tick's fault flags in words ('' when none), with the readings that raised them.

    Args:
        flags: The tick's fault flags.
        record: Its sample (description order).
        foot_reason: Why each foot sensor is distrusted (``FOOT_*``), ``LEGS`` order.
        quaternion_tolerance: The estimator's unit-norm tolerance.
        quaternion_timeout_s: Its time [s] on the gyroscope alone.
        quaternion_note: What the estimator does without the IMU's quaternion.
        weight_evidence: The feet's calibrated forces' last sum and the robot's weight [N]
            (the :data:`FOOT_WEIGHT` fault quotes them).
    """
    parts = []
    if flags & NO_DATA:
        parts.append("no sensor sample this period")
    if flags & STALE:
        parts.append(f"stale sample (tick {record.tick} repeated)")
    if flags & JOINTS_BAD:
        bad = [i for i in range(12)
               if not (math.isfinite(record.q[i]) and math.isfinite(record.dq[i]))]
        parts.append(f"joint readings non-finite at {bad}")
    if flags & GYRO_BAD:
        parts.append(f"gyroscope non-finite ({record.gyroscope_rad_s.tolist()})")
    if flags & ACCEL_BAD:
        parts.append(f"accelerometer non-finite ({record.accelerometer_m_s2.tolist()}): "
                     "predicting without it")
    if flags & QUATERNION_NON_FINITE:
        parts.append(f"IMU quaternion non-finite ({record.imu_quaternion_wxyz.tolist()}): "
                     f"{quaternion_note}")
    if flags & QUATERNION_NOT_UNIT:
        norm = float(np.linalg.norm(record.imu_quaternion_wxyz))
        parts.append(f"IMU quaternion not unit (norm {norm:.4g}, tolerance "
                     f"{quaternion_tolerance:g}): {quaternion_note}")
    if flags & QUATERNION_TIMEOUT:
        parts.append(f"no valid IMU quaternion for more than {quaternion_timeout_s:g} s")
    for i, leg in enumerate(LEGS):
        reason = int(foot_reason[i])
        if reason != FOOT_OK:
            value = record.foot_force[i]
            parts.append(f"{leg} foot-force sensor {_FOOT_REASONS[reason].format(value=value)}: "
                         "contact from the schedule")
    if flags & FOOT_WEIGHT:
        total, weight = weight_evidence
        parts.append(f"foot-force evidence contradicts the weight (the feet read {total:.0f} N "
                     f"in all, the robot weighs {weight:.0f} N): foot-force calibration wrong "
                     "or sensors broken; contact from the schedule")
    return "; ".join(parts)
