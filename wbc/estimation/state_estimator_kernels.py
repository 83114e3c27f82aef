"""The linear Kalman filter's compiled tick and start (:class:`wbc.LinearKalmanFilter`, ``kf``).

The orientation follows the IMU's quaternion through a complementary filter on the
gyroscope; the position and velocity are three independent 6-state filters, one per world
axis, corrected one scalar at a time (see :mod:`wbc.estimation.state_estimator`). The
sample's checks, contacts, foot motion and outputs are :mod:`wbc.estimation.shared_kernels`'.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.quaternion_kernels import (
    quat_exp,
    quat_log,
    quat_multiply,
    quat_normalize,
    quat_rotation,
)
from wbc.estimation.kernel_groups import SHARED_WORK
from wbc.estimation.shared_kernels import (
    account_trust,
    check_sample,
    foot_motion,
    legs_and_contacts,
    sample_of,
    start_pose,
    write_outputs,
)
from wbc.estimation.state_estimate import QUATERNION_TIMEOUT

# The kernel's state vector: orientation, gyro bias, yaw alignment, last good readings,
# bookkeeping.
_QUAT, _BIAS, _ALIGN, _OMEGA, _ACCEL = 0, 4, 7, 11, 14
_QUAT_AGE_S = 17
_STATE_SIZE = 18
#: The tick's and the start's work arrays, by name and shape (a work record:
#: :func:`wbc.core.kernel_records.work_record`): the shared kernels' (:data:`SHARED_WORK`),
#: then the orientation's quaternion steps and the world acceleration, the scalar updates'
#: gain and ``P`` column, the orientation's matrix, and the start's IMU and feet positions.
WORK_SHAPES: dict[str, tuple[int, ...]] = {
    **SHARED_WORK, "step": (4,), "product": (4,), "measured": (4,), "inverse": (4,),
    "error": (3,), "world_accel": (3,), "gain": (6,), "projected": (6,), "rotation": (3, 3),
    "imu_position": (3,), "feet": (4, 3),
}


class KalmanArrays(NamedTuple):
    """The filter's own arrays (in/out): ``state`` (:data:`_STATE_SIZE`: orientation
    (w, x, y, z), gyro bias, yaw alignment, last good angular velocity and specific force,
    the quaternion's age), and the three axes' filters, ``x`` (3, 6) and ``P`` (3, 6, 6):
    ``[IMU position, IMU velocity, feet 0..3]``."""

    state: np.ndarray
    x: np.ndarray
    P: np.ndarray


@numba.njit(cache=True)
def _scalar_update(x, P, plus, minus, measured, variance, gain, projected):  # pragma: no cover
    """Kalman update of one axis' filter with ``x[plus] - x[minus] = measured`` (``minus``
    -1: ``x[plus] = measured``), measurement variance ``variance``."""
    n = x.shape[0]
    for r in range(n):
        projected[r] = P[r, plus] - P[r, minus] if minus >= 0 else P[r, plus]
    innovation = measured - (x[plus] - x[minus] if minus >= 0 else x[plus])
    s = projected[plus] - (projected[minus] if minus >= 0 else 0.0) + variance
    for r in range(n):
        gain[r] = projected[r] / s
        x[r] += gain[r] * innovation
    for r in range(n):
        for c in range(n):
            P[r, c] -= gain[r] * projected[c]


@numba.njit(cache=True)
def _estimate(sample, schedule, params, legs, filter_state, sensors, outputs,
              work):  # pragma: no cover - compiled
    """One tick of the estimator (see the module docstring); returns the fault flags.

    Args:
        sample: This tick's :class:`~wbc.estimation.kernel_groups.Sample`.
        schedule: Each foot's normal-force bound [N] (4,).
        params: The parameter record (``LinearKalmanFilter``'s config fields by name, and
            ``control_period_s``).
        legs: :class:`~wbc.estimation.kernel_groups.Legs`.
        filter_state: In/out :class:`KalmanArrays`.
        sensors: In/out :class:`~wbc.estimation.kernel_groups.SensorState`.
        outputs: Out :class:`~wbc.estimation.kernel_groups.Outputs`.
        work: The work record (:data:`WORK_SHAPES`): the tick allocates nothing.
    """
    p, w = params[0], work[0]
    state, x, P = filter_state.state, filter_state.x, filter_state.P
    quat_tol, quat_timeout, radius = (p.quaternion_tolerance, p.quaternion_timeout_s,
                                      p.foot_radius_m)
    sigma_pos, sigma_vel, sigma_h = (p.foot_position_noise_m, p.foot_velocity_noise_m_s,
                                     p.foot_height_noise_m)
    swing_scale, min_weight = p.swing_noise_scale, p.min_contact_weight
    clock, weight, imu_offset = sensors.clock, outputs.contact, legs.imu_offset
    gyro_in, accel_in = sample.gyroscope, sample.accelerometer
    flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok = check_sample(
        sample, clock, p.control_period_s, quat_tol)
    # --- orientation: gyroscope, pulled towards the IMU's quaternion
    quat = state[_QUAT:_QUAT + 4]
    bias = state[_BIAS:_BIAS + 3]
    omega = state[_OMEGA:_OMEGA + 3]
    if gyro_ok:
        for k in range(3):
            omega[k] = gyro_in[k] - bias[k]
    step, product, measured, inverse = w.step, w.product, w.measured, w.inverse
    error, world_accel, rotation = w.error, w.world_accel, w.rotation
    relative, velocity, rolling = w.relative, w.velocity, w.rolling
    quat_exp(omega[0] * dt, omega[1] * dt, omega[2] * dt, step)
    quat_multiply(quat, step, product)
    quat[:] = product
    if quat_ok:
        quat_multiply(state[_ALIGN:_ALIGN + 4], sample.quaternion, measured)
        quat_normalize(measured)
        inverse[0] = quat[0]
        for k in range(1, 4):
            inverse[k] = -quat[k]
        quat_multiply(inverse, measured, product)
        quat_log(product, error)
        tau_q = p.orientation_time_constant_s
        gain = min(1.0, dt / tau_q)
        quat_exp(gain * error[0], gain * error[1], gain * error[2], step)
        quat_multiply(quat, step, product)
        quat[:] = product
        for k in range(3):
            bias[k] -= error[k] * dt / (tau_q * p.gyro_bias_time_constant_s)
        state[_QUAT_AGE_S] = 0.0
    else:
        state[_QUAT_AGE_S] += dt
        if state[_QUAT_AGE_S] > quat_timeout:
            flags |= QUATERNION_TIMEOUT
    quat_normalize(quat)
    quat_rotation(quat, rotation)
    # --- legs and contacts
    flags |= legs_and_contacts(joints_ok, new, dt, sample, schedule, p, legs, sensors, outputs,
                               w.legs)
    foot_motion(rotation, omega, outputs.joint_dq, imu_offset, legs, radius, relative,
                velocity, rolling, w)
    # --- prediction: the accelerometer, world frame
    accel = state[_ACCEL:_ACCEL + 3]
    world_accel[:] = 0.0
    if accel_ok:
        for k in range(3):
            accel[k] = accel_in[k]
        for r in range(3):
            world_accel[r] = (rotation[r, 0] * accel[0] + rotation[r, 1] * accel[1]
                              + rotation[r, 2] * accel[2])
        world_accel[2] -= GRAVITY_M_S2
    sigma_p, sigma_v = p.position_process_noise, p.velocity_process_noise
    sigma_f = p.foot_process_noise
    gain_vector, projected = w.gain, w.projected
    for a in range(3):
        xa = x[a]
        Pa = P[a]
        xa[0] += xa[1] * dt + 0.5 * world_accel[a] * dt * dt
        xa[1] += world_accel[a] * dt
        for c in range(6):  # F P
            Pa[0, c] += dt * Pa[1, c]
        for r in range(6):  # (F P) F^T
            Pa[r, 0] += dt * Pa[r, 1]
        Pa[0, 0] += sigma_p * sigma_p * dt
        Pa[1, 1] += sigma_v * sigma_v * dt
        for i in range(4):
            f = 2 + i
            if weight[i] >= min_weight:
                xa[f] += rolling[i, a] * dt
                Pa[f, f] += sigma_f * sigma_f * dt
            else:  # a free foot is where the kinematics put it
                xa[f] = xa[0] + relative[i, a]
                for c in range(6):
                    Pa[f, c] = Pa[0, c]
                for r in range(6):
                    Pa[r, f] = Pa[r, 0]
                Pa[f, f] = Pa[0, 0] + sigma_pos * sigma_pos
    # --- correction: each foot's kinematics, one scalar at a time
    if joints_ok:
        for i in range(4):
            if weight[i] < min_weight:
                continue
            scale = swing_scale ** (1.0 - min(1.0, weight[i]))
            f = 2 + i
            for a in range(3):
                _scalar_update(x[a], P[a], f, 0, relative[i, a], sigma_pos * sigma_pos * scale,
                               gain_vector, projected)
                _scalar_update(x[a], P[a], 1, -1, velocity[i, a],
                               sigma_vel * sigma_vel * scale, gain_vector, projected)
            _scalar_update(x[2], P[2], f, -1, radius, sigma_h * sigma_h * scale, gain_vector,
                           projected)
    write_outputs(rotation, quat, omega, x[0, 0], x[1, 0], x[2, 0], x[0, 1], x[1, 1], x[2, 1],
                  imu_offset, outputs, w)
    account_trust(flags, dt, clock)
    return flags


@numba.njit(cache=True)
def _estimate_from_header(header, readings, schedule, params, legs, filter_state, sensors,
                          outputs, work):  # pragma: no cover - compiled
    """:func:`_estimate` on the sample of ``header`` and ``readings``
    (:func:`~wbc.estimation.shared_kernels.sample_of`): the linear Kalman filter's tick as one
    compiled call whose arrays are read from a table of addresses
    (:class:`wbc.core.compiled_program.CompiledProgram`), the sample's scalars from ``header``."""
    return _estimate(sample_of(header, readings), schedule, params, legs, filter_state,
                     sensors, outputs, work)


@numba.njit(cache=True)
def _start(quat_in, q_in, params, legs, filter_state, base_x, base_y, keep_yaw,
           work):  # pragma: no cover - compiled
    """Start on four loaded feet, at rest, where :func:`start_pose` puts the base and the
    feet; the groups are :func:`_estimate`'s."""
    p, w = params[0], work[0]
    state, x, P = filter_state.state, filter_state.x, filter_state.P
    sigma_pos, sigma_h = p.foot_position_noise_m, p.foot_height_noise_m
    imu_position, feet = w.imu_position, w.feet
    start_pose(quat_in, q_in, keep_yaw, base_x, base_y, p.foot_radius_m, legs,
               state[_ALIGN:_ALIGN + 4], state[_QUAT:_QUAT + 4], imu_position, feet, w)
    x[:, :] = 0.0
    P[:, :, :] = 0.0
    for a in range(3):
        x[a, 0] = imu_position[a]
        P[a, 0, 0] = (sigma_h * sigma_h) if a == 2 else 1e-8
        P[a, 1, 1] = 1e-4  # at rest, within 1 cm/s
        for i in range(4):
            f = 2 + i
            x[a, f] = feet[i, a]
            P[a, f, 0] = P[a, 0, f] = P[a, 0, 0]
            P[a, f, f] = P[a, 0, 0] + sigma_pos * sigma_pos
            for k in range(i):
                P[a, f, 2 + k] = P[a, 2 + k, f] = P[a, 0, 0]
    state[_BIAS:_BIAS + 3] = 0.0
    state[_OMEGA:_OMEGA + 3] = 0.0
    state[_ACCEL:_ACCEL + 3] = 0.0
    state[_QUAT_AGE_S] = 0.0
