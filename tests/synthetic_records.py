"""Sensor records of a GO2 at rest, made from a configuration: the estimators' unit tests."""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from wbc.estimation.state_estimate import StateEstimate
from wbc.estimation.state_estimator import EstimatorBase
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS, Go2Description
from wbc.robot_io.sensor_record import SensorRecord

LOADED = np.full(4, 200.0)  # the contact schedule of four loaded feet [N]
LOADED_COUNT = 110.0  # a foot sensor's count under about 40 N


def pose(roll_deg: float = 0.0, pitch_deg: float = 0.0, yaw_deg: float = 0.0) -> np.ndarray:
    """The standing configuration, its base turned by roll, pitch and yaw [deg]."""
    q = Go2Description.default().pose("standing")
    rotation = pin.rpy.rpyToMatrix(*np.radians([roll_deg, pitch_deg, yaw_deg]))
    q[3:7] = pin.Quaternion(rotation).coeffs()
    return q


def record(q: np.ndarray, *, tick: int, period_s: float = 1e-3, gyro=(0.0, 0.0, 0.0),
           feet: Any = None) -> SensorRecord:
    """What a GO2 at rest in configuration ``q`` measures: noise-free but for the foot
    counts, which a live sensor's noise changes (by default 108 to 112 on every foot)."""
    if feet is None:
        feet = LOADED_COUNT + (tick % 5) - 2
    x, y, z, w = q[3:7]
    rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
    return SensorRecord(
        stamp_s=tick * period_s, tick=tick, imu_quaternion_wxyz=[w, x, y, z],
        gyroscope_rad_s=gyro, accelerometer_m_s2=rotation.T @ [0.0, 0.0, 9.81],
        q=q[7:], dq=np.zeros(12), tau_est=np.zeros(12), foot_force=np.full(4, feet, float))


def expected_height(q: np.ndarray) -> float:
    """The base height that puts the feet's sphere centres at one radius above the floor."""
    model = Go2Description.default().model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    feet = [data.oMf[model.getFrameId(FOOT_FRAMES[leg])].translation[2] for leg in LEGS]
    return float(q[2] + FOOT_RADIUS_M - np.mean(feet))


def started(kind: type[EstimatorBase], q: np.ndarray | None = None,
            **overrides: Any) -> EstimatorBase:
    """An estimator of ``kind`` started on the record of ``q`` (standing by default)."""
    estimator = kind(**overrides)
    estimator.reset(record(pose() if q is None else q, tick=0))
    return estimator


def run(estimator: EstimatorBase, q: np.ndarray, ticks: int, first_tick: int = 1,
        **kwargs: Any) -> StateEstimate:
    """``ticks`` records of ``q`` at rest, four feet loaded; the last estimate."""
    for tick in range(first_tick, first_tick + ticks):
        estimate = estimator.update(record(q, tick=tick, **kwargs), LOADED)
    return estimate
