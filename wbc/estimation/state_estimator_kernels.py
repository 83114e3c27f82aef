"""The linear Kalman filter's compiled tick and start (:class:`wbc.StateEstimator`, ``kf``).

The orientation follows the IMU's quaternion through a complementary filter on the
gyroscope; the position and velocity are three independent 6-state filters, one per world
axis, corrected one scalar at a time (see :mod:`wbc.estimation.state_estimator`). The
sample's checks, contacts, foot motion and outputs are :mod:`wbc.estimation.shared_kernels`'.
"""

from __future__ import annotations

import numba

from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.quaternion_kernels import (
    quat_exp,
    quat_log,
    quat_multiply,
    quat_normalize,
    quat_rotation,
)
from wbc.estimation.shared_kernels import (
    START_WORK_SIZE,
    account_trust,
    check_sample,
    foot_motion,
    legs_and_contacts,
    start_pose,
    write_outputs,
)
from wbc.estimation.state_estimate import QUATERNION_TIMEOUT

# The kernel's state vector: orientation, gyro bias, yaw alignment, last good readings,
# bookkeeping.
_QUAT, _BIAS, _ALIGN, _OMEGA, _ACCEL = 0, 4, 7, 11, 14
_QUAT_AGE_S = 17
_STATE_SIZE = 18
#: Scratch space of the tick's kernel and of the start [floats].
_WORK_SIZE = 136


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
def _estimate(fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, force_in,
              schedule, dt_nominal, params, imu_offset, rotations, translations, axes,
              foot_offsets, foot_position, foot_jacobian, foot_angular_jacobian, clock, state,
              x, P, foot_contact, foot_same_s, foot_good_s, foot_reason, foot_last, foot_cal,
              joint_q, joint_dq, q_out, v_out, weight, work):  # pragma: no cover - compiled
    """One tick of the estimator (see the module docstring); returns the fault flags.

    ``state`` holds the orientation (w, x, y, z), the gyro bias, the yaw alignment, the last
    good angular velocity and specific force, and the quaternion's age; ``x`` (3, 6) and
    ``P`` (3, 6, 6) are the three axes' filters: ``[IMU position, IMU velocity, feet 0..3]``.
    ``work`` (:data:`_WORK_SIZE`) is scratch space: the tick allocates nothing.
    """
    (tau_q, tau_b, quat_tol, quat_timeout, sigma_p, sigma_v, sigma_f, sigma_pos, sigma_vel,
     sigma_h, swing_scale, min_weight, radius) = (
        params[0], params[1], params[2], params[3], params[4], params[5], params[6],
        params[7], params[8], params[9], params[10], params[11], params[12])
    flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok = check_sample(
        fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, clock, dt_nominal,
        quat_tol)
    # --- orientation: gyroscope, pulled towards the IMU's quaternion
    quat = state[_QUAT:_QUAT + 4]
    bias = state[_BIAS:_BIAS + 3]
    omega = state[_OMEGA:_OMEGA + 3]
    if gyro_ok:
        for k in range(3):
            omega[k] = gyro_in[k] - bias[k]
    step, product, measured, inverse = work[0:4], work[4:8], work[8:12], work[12:16]
    error, world_accel = work[16:19], work[19:22]
    gain_vector, projected = work[22:28], work[28:34]
    rotation = work[34:43].reshape((3, 3))
    relative = work[43:55].reshape((4, 3))
    velocity = work[55:67].reshape((4, 3))
    rolling = work[67:79].reshape((4, 3))
    legs_work = work[79:115].reshape((4, 3, 3))
    motion_work = work[115:127].reshape((4, 3))
    output_work = work[127:136].reshape((3, 3))
    quat_exp(omega[0] * dt, omega[1] * dt, omega[2] * dt, step)
    quat_multiply(quat, step, product)
    quat[:] = product
    if quat_ok:
        quat_multiply(state[_ALIGN:_ALIGN + 4], quat_in, measured)
        quat_normalize(measured)
        inverse[0] = quat[0]
        for k in range(1, 4):
            inverse[k] = -quat[k]
        quat_multiply(inverse, measured, product)
        quat_log(product, error)
        gain = min(1.0, dt / tau_q)
        quat_exp(gain * error[0], gain * error[1], gain * error[2], step)
        quat_multiply(quat, step, product)
        quat[:] = product
        for k in range(3):
            bias[k] -= error[k] * dt / (tau_q * tau_b)
        state[_QUAT_AGE_S] = 0.0
    else:
        state[_QUAT_AGE_S] += dt
        if state[_QUAT_AGE_S] > quat_timeout:
            flags |= QUATERNION_TIMEOUT
    quat_normalize(quat)
    quat_rotation(quat, rotation)
    # --- legs and contacts
    flags |= legs_and_contacts(joints_ok, new, dt, q_in, dq_in, force_in, schedule, params,
                               rotations, translations, axes, foot_offsets, foot_position,
                               foot_jacobian, foot_angular_jacobian, legs_work, joint_q,
                               joint_dq, foot_contact, foot_same_s, foot_good_s, foot_reason,
                               foot_last, foot_cal, weight)
    foot_motion(rotation, omega, joint_dq, imu_offset, foot_position, foot_jacobian,
                foot_angular_jacobian, radius, relative, velocity, rolling, motion_work)
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
                  imu_offset, joint_q, joint_dq, q_out, v_out, output_work)
    account_trust(flags, dt, clock)
    return flags


@numba.njit(cache=True)
def _start(quat_in, q_in, params, imu_offset, rotations, translations, axes, foot_offsets,
           foot_position, foot_jacobian, foot_angular_jacobian, state, x, P, base_x, base_y,
           keep_yaw, work):  # pragma: no cover - compiled
    """Start on four loaded feet, at rest, where :func:`start_pose` puts the base and the
    feet; ``work`` is scratch space (:data:`_WORK_SIZE`)."""
    sigma_pos, sigma_h, radius = params[7], params[9], params[12]
    imu_position, feet = work[0:3], work[3:15].reshape((4, 3))
    start_pose(quat_in, q_in, keep_yaw, base_x, base_y, radius, imu_offset, rotations,
               translations, axes, foot_offsets, foot_position, foot_jacobian,
               foot_angular_jacobian, state[_ALIGN:_ALIGN + 4], state[_QUAT:_QUAT + 4],
               imu_position, feet, work[15:15 + START_WORK_SIZE])
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
