"""The invariant EKF's compiled tick and start (:class:`wbc.InvariantEkf`, ``inekf``).

Prediction with the gyroscope and the accelerometer, correction with each contact foot's
position in the body frame, on the group (:mod:`wbc.estimation.invariant_ekf_group`); the
sample's checks, contacts, foot motion and outputs are :mod:`wbc.estimation.shared_kernels`'.
"""

from __future__ import annotations

import numba

from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.quaternion_kernels import quat_exp, quat_multiply, quat_normalize, quat_rotation
from wbc.estimation.invariant_ekf_group import (
    _ABIAS,
    _ACCEL,
    _BA,
    _BG,
    _D,
    _DIM,
    _FEET,
    _GBIAS,
    _GYRO,
    _P,
    _POS,
    _QUAT,
    _R,
    _V,
    _VEL,
    _add_process_noise,
    _correct,
    _correct_scalar,
    _propagate_covariance,
    _skew_times,
    _transition_blocks,
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

#: Scratch space of the tick's kernel (see :func:`_estimate`) and of the start [floats].
_WORK_SIZE = 497


@numba.njit(cache=True)
def _estimate(fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, force_in,
              schedule, dt_nominal, params, imu_offset, rotations, translations, axes,
              foot_offsets, foot_position, foot_jacobian, foot_angular_jacobian, clock, x, P,
              foot_contact, foot_same_s, foot_good_s, foot_reason, foot_last, foot_cal,
              joint_q, joint_dq, q_out, v_out, weight, work):  # pragma: no cover - compiled
    """One tick of the invariant EKF (see the module docstring); returns the fault flags.

    ``x`` (:data:`_X_SIZE`) is the mean, ``P`` (27, 27) the right-invariant error's
    covariance; ``work`` (:data:`_WORK_SIZE`) is scratch space: the tick allocates nothing.
    """
    (sigma_k, sigma_pos, sigma_vel, sigma_h, swing_scale, min_weight, radius, quat_tol) = (
        params[5], params[6], params[7], params[8], params[9], params[10], params[11],
        params[12])
    flags, dt, new, _quaternion_ok, gyro_ok, accel_ok, joints_ok = check_sample(
        fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, clock, dt_nominal,
        quat_tol)
    rotation = work[0:9].reshape((3, 3))
    omega, accel, turned = work[9:12], work[12:15], work[15:18]
    relative = work[18:30].reshape((4, 3))
    velocity = work[30:42].reshape((4, 3))
    rolling = work[42:54].reshape((4, 3))
    legs_work = work[54:90].reshape((4, 3, 3))
    motion_work = work[90:102].reshape((4, 3))
    output_work = work[102:111].reshape((3, 3))
    blocks = work[111:219].reshape((12, 3, 3))
    step, product = work[219:223], work[223:227]
    HP = work[227:308].reshape((3, 27))
    S = work[308:317].reshape((3, 3))
    innovation, body, kin = work[317:320], work[320:323], work[323:332].reshape((3, 3))
    height_row = work[332:359]
    correction_work = work[359:497]
    quat = x[_QUAT:_QUAT + 4]
    gbias, abias = x[_GBIAS:_GBIAS + 3], x[_ABIAS:_ABIAS + 3]
    # --- inputs: the last good readings stand in for bad or missing ones
    if gyro_ok:
        x[_GYRO:_GYRO + 3] = gyro_in
    for k in range(3):
        omega[k] = x[_GYRO + k] - gbias[k]
    quat_rotation(quat, rotation)
    if accel_ok:
        x[_ACCEL:_ACCEL + 3] = accel_in
        for k in range(3):
            accel[k] = accel_in[k] - abias[k]
    else:  # no acceleration: the specific force is gravity's
        for k in range(3):
            accel[k] = GRAVITY_M_S2 * rotation[2, k]
    flags |= legs_and_contacts(joints_ok, new, dt, q_in, dq_in, force_in, schedule, params,
                               rotations, translations, axes, foot_offsets, foot_position,
                               foot_jacobian, foot_angular_jacobian, legs_work, joint_q,
                               joint_dq, foot_contact, foot_same_s, foot_good_s, foot_reason,
                               foot_last, foot_cal, weight)
    # --- prediction: the covariance on the unpropagated mean, then the mean
    _transition_blocks(rotation, x, dt, blocks)
    _propagate_covariance(P, blocks)
    _add_process_noise(P, x, params, weight, min_weight, dt)
    phi0, phi1, phi2 = omega[0] * dt, omega[1] * dt, omega[2] * dt
    # The specific force over the step in the starting frame, to first order in the turn:
    # Gamma_1 a = a + phi x a / 2 for the velocity, Gamma_2 a = a / 2 + phi x a / 6.
    _skew_times(omega, accel, turned)
    for r in range(3):
        a1 = (rotation[r, 0] * (accel[0] + 0.5 * dt * turned[0])
              + rotation[r, 1] * (accel[1] + 0.5 * dt * turned[1])
              + rotation[r, 2] * (accel[2] + 0.5 * dt * turned[2]))
        a2 = (rotation[r, 0] * (0.5 * accel[0] + dt * turned[0] / 6.0)
              + rotation[r, 1] * (0.5 * accel[1] + dt * turned[1] / 6.0)
              + rotation[r, 2] * (0.5 * accel[2] + dt * turned[2] / 6.0))
        if r == 2:
            a1 -= GRAVITY_M_S2
            a2 -= 0.5 * GRAVITY_M_S2
        x[_POS + r] += x[_VEL + r] * dt + a2 * dt * dt
        x[_VEL + r] += a1 * dt
    quat_exp(phi0, phi1, phi2, step)
    quat_multiply(quat, step, product)
    quat_normalize(product)
    quat[:] = product
    quat_rotation(quat, rotation)
    foot_motion(rotation, omega, joint_dq, imu_offset, foot_position, foot_jacobian,
                foot_angular_jacobian, radius, relative, velocity, rolling, motion_work)
    for i in range(4):
        f = _FEET + 3 * i
        e = _D + 3 * i
        if weight[i] >= min_weight:  # a stance foot's centre rolls with its sphere
            for k in range(3):
                x[f + k] += rolling[i, k] * dt
        else:  # a free foot is where the kinematics put it: its error is the position's
            for k in range(3):
                x[f + k] = x[_POS + k] + relative[i, k]
            for r in range(3):
                for c in range(_DIM):
                    P[e + r, c] = P[_P + r, c]
            for r in range(_DIM):
                for c in range(3):
                    P[r, e + c] = P[r, _P + c]
            for r in range(3):
                for c in range(3):
                    P[e + r, e + c] = P[_P + r, _P + c]
                P[e + r, e + r] += sigma_pos * sigma_pos
    # --- correction: each contact foot's position in the body frame, one foot at a time
    if joints_ok:
        for i in range(4):
            if weight[i] < min_weight:
                continue
            scale = swing_scale ** (1.0 - min(1.0, weight[i]))
            f = _FEET + 3 * i
            e = _D + 3 * i
            # Noise in the world: R (sigma_k^2 J J^T + sigma_pos^2 I) R^T, scaled.
            for r in range(3):
                for c in range(3):
                    kin[r, c] = (rotation[r, 0] * foot_jacobian[i, 0, c]
                                 + rotation[r, 1] * foot_jacobian[i, 1, c]
                                 + rotation[r, 2] * foot_jacobian[i, 2, c])
            for k in range(3):
                body[k] = foot_position[i, k] - imu_offset[k]
            for r in range(3):
                # Innovation R y - (d - p), with the orientation as corrected so far.
                innovation[r] = ((rotation[r, 0] * body[0] + rotation[r, 1] * body[1]
                                  + rotation[r, 2] * body[2]) - (x[f + r] - x[_POS + r]))
            for k in range(3):  # H = [-I on p, I on d_i]
                for c in range(_DIM):
                    HP[k, c] = P[e + k, c] - P[_P + k, c]
            for r in range(3):
                for c in range(3):
                    S[r, c] = (HP[r, e + c] - HP[r, _P + c]
                               + scale * sigma_k * sigma_k * (kin[r, 0] * kin[c, 0]
                                                              + kin[r, 1] * kin[c, 1]
                                                              + kin[r, 2] * kin[c, 2]))
                S[r, r] += scale * sigma_pos * sigma_pos
            _correct(x, P, HP, S, innovation, correction_work)
            quat_rotation(quat, rotation)
            if sigma_vel > 0.0:
                # The IMU velocity the rolling foot implies (world): H = I on v.
                for k in range(3):
                    for c in range(_DIM):
                        HP[k, c] = P[_V + k, c]
                for r in range(3):
                    innovation[r] = velocity[i, r] - x[_VEL + r]
                    for c in range(3):
                        S[r, c] = HP[r, _V + c]
                    S[r, r] += scale * sigma_vel * sigma_vel
                _correct(x, P, HP, S, innovation, correction_work)
                quat_rotation(quat, rotation)
            if sigma_h > 0.0:
                # The foot centre's height r on a flat floor: d_z - r = 0. Not invariant:
                # the error's z-part is e_z . (xi_d - d^ xi_R), h = (d_y, -d_x, 0) on R.
                dx, dy = x[f], x[f + 1]
                for c in range(_DIM):
                    height_row[c] = dy * P[_R, c] - dx * P[_R + 1, c] + P[e + 2, c]
                variance = (dy * height_row[_R] - dx * height_row[_R + 1] + height_row[e + 2]
                            + scale * sigma_h * sigma_h)
                _correct_scalar(x, P, height_row, variance, radius - x[f + 2],
                                correction_work)
                quat_rotation(quat, rotation)
    # Keep the covariance symmetric against rounding.
    for r in range(_DIM):
        for c in range(r):
            mean = 0.5 * (P[r, c] + P[c, r])
            P[r, c] = mean
            P[c, r] = mean
    for k in range(3):
        omega[k] = x[_GYRO + k] - gbias[k]
    write_outputs(rotation, quat, omega, x[_POS], x[_POS + 1], x[_POS + 2], x[_VEL],
                  x[_VEL + 1], x[_VEL + 2], imu_offset, joint_q, joint_dq, q_out, v_out,
                  output_work)
    account_trust(flags, dt, clock)
    return flags


@numba.njit(cache=True)
def _start(quat_in, q_in, params, imu_offset, rotations, translations, axes, foot_offsets,
           foot_position, foot_jacobian, foot_angular_jacobian, x, P, base_x, base_y,
           keep_yaw, work):  # pragma: no cover - compiled
    """Start on four loaded feet, at rest, where :func:`start_pose` puts the base and the
    feet, biases 0, and the priors' covariance; ``work`` is scratch space (:data:`_WORK_SIZE`)."""
    sigma_pos, radius = params[6], params[11]
    tilt, gyro_bias, accel_bias = params[13], params[14], params[15]
    x[:] = 0.0
    start_pose(quat_in, q_in, keep_yaw, base_x, base_y, radius, imu_offset, rotations,
               translations, axes, foot_offsets, foot_position, foot_jacobian,
               foot_angular_jacobian, work[0:4], x[_QUAT:_QUAT + 4], x[_POS:_POS + 3],
               x[_FEET:_FEET + 12].reshape((4, 3)), work[4:4 + START_WORK_SIZE])
    x[_ACCEL + 2] = GRAVITY_M_S2
    P[:, :] = 0.0
    # Roll and pitch as good as the IMU's attitude filter; the yaw is 0 by definition.
    P[_R, _R] = P[_R + 1, _R + 1] = tilt * tilt
    P[_R + 2, _R + 2] = 1e-8
    for k in range(3):
        P[_V + k, _V + k] = 1e-4  # at rest, within 1 cm/s
        P[_P + k, _P + k] = sigma_pos * sigma_pos if k == 2 else 1e-8
        P[_BG + k, _BG + k] = gyro_bias * gyro_bias
        P[_BA + k, _BA + k] = accel_bias * accel_bias
    # The position is known in the world, the orientation is not: the right-invariant error
    # measures the position about the world's origin, xi_p = dp + p^ xi_R. (Left out, a
    # later roll or pitch correction would swing the base about the origin.)
    hat = work[0:9].reshape((3, 3))  # p^
    px, py, pz = x[_POS], x[_POS + 1], x[_POS + 2]
    hat[0, 0], hat[0, 1], hat[0, 2] = 0.0, -pz, py
    hat[1, 0], hat[1, 1], hat[1, 2] = pz, 0.0, -px
    hat[2, 0], hat[2, 1], hat[2, 2] = -py, px, 0.0
    for r in range(3):
        for c in range(3):
            P[_P + r, _R + c] = P[_R + c, _P + r] = hat[r, c] * P[_R + c, _R + c]
            for k in range(3):
                P[_P + r, _P + c] += hat[r, k] * P[_R + k, _R + k] * hat[c, k]
    # A foot's error is the position's plus its kinematic noise (right-invariant error).
    for i in range(4):
        e = _D + 3 * i
        for r in range(3):
            for c in range(3):
                P[e + r, _R + c] = P[_R + c, e + r] = P[_P + r, _R + c]
                P[e + r, _P + c] = P[_P + r, e + c] = P[_P + r, _P + c]
                for j in range(4):
                    P[e + r, _D + 3 * j + c] = P[_P + r, _P + c]
            P[e + r, e + r] += sigma_pos * sigma_pos
