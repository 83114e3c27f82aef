"""The simulated sensors' compiled sampler's named groups (:mod:`sim.sensors`' kernel reads
them by name): what the plant gives a sample, where the sensors read it, their drifting state
and the record's arrays a sample fills."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class PlantReading(NamedTuple):
    """What the plant gives a sample: MuJoCo's free-joint state ``qpos``, ``qvel`` (world
    linear velocity, body angular velocity), each joint's applied torque [N m] (robot joint
    order), each foot's normal force [N] (``LEGS`` order), the time since the previous
    sample [s] and whether there was one (else the IMU site is taken as not accelerating)."""

    qpos: np.ndarray
    qvel: np.ndarray
    actuator_force: np.ndarray
    touch: np.ndarray
    dt: float
    has_previous: bool


class SensorSites(NamedTuple):
    """Where the sensors read the plant: each joint's qpos and qvel index (robot joint
    order), the row of ``touch`` of each foot (robot leg order), the IMU in the base [m]."""

    joint_qpos: np.ndarray
    joint_dof: np.ndarray
    leg_rows: np.ndarray
    imu_offset: np.ndarray


class SensorDrift(NamedTuple):
    """The sensors' state between samples (in/out): the IMU site's last world velocity, the
    walking biases, the attitude filter's quaternion ``(w, x, y, z)`` and integral term
    [rad/s]."""

    site_velocity: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    attitude: np.ndarray
    integral: np.ndarray


class RecordArrays(NamedTuple):
    """Out: a :class:`wbc.SensorRecord`'s arrays the sample fills."""

    quaternion: np.ndarray
    gyroscope: np.ndarray
    accelerometer: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau: np.ndarray
    feet: np.ndarray
