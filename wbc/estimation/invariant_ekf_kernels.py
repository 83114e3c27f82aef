"""The invariant EKF's compiled tick and start (:class:`wbc.InvariantEkf`, ``inekf``).

Prediction with the gyroscope and the accelerometer, correction with each contact foot's
position in the body frame, on the group (:mod:`wbc.estimation.invariant_ekf_group`); the
sample's checks, contacts, foot motion and outputs are :mod:`wbc.estimation.shared_kernels`'.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.quaternion_kernels import quat_exp, quat_multiply, quat_normalize, quat_rotation
from wbc.estimation.invariant_ekf_group import (
    _ABIAS,
    _ACCEL,
    _BA,
    _BG,
    _BLOCKS,
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
    CORRECTION_WORK,
    _add_process_noise,
    _correct,
    _correct_scalar,
    _propagate_covariance,
    _skew_times,
    _transition_blocks,
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

#: The tick's and the start's work arrays, by name and shape (a work record:
#: :func:`wbc.core.kernel_records.work_record`): the shared kernels' (:data:`SHARED_WORK`),
#: the corrections' (:data:`CORRECTION_WORK`), then the orientation's matrix, the inputs
#: (angular velocity, specific force, their cross product), the transition's blocks, the
#: quaternion step, a foot's measurement (``H P``, ``S``, innovation, body-frame position,
#: kinematic Jacobian in the world, the height's row) and the start's ``p^``.
WORK_SHAPES: dict[str, tuple[int, ...]] = {
    **SHARED_WORK, **CORRECTION_WORK, "rotation": (3, 3), "omega": (3,), "accel": (3,),
    "turned": (3,), "blocks": (_BLOCKS, 3, 3), "step": (4,), "product": (4,),
    "HP": (3, _DIM), "S": (3, 3), "innovation": (3,), "body": (3,), "kin": (3, 3),
    "height_row": (_DIM,), "align": (4,), "hat": (3, 3),
}


class InvariantArrays(NamedTuple):
    """The filter's own arrays (in/out): the mean ``x`` (:data:`_X_SIZE`) and the
    right-invariant error's covariance ``P`` (27, 27)."""

    x: np.ndarray
    P: np.ndarray


@numba.njit(cache=True)
def _estimate(sample, schedule, params, legs, filter_state, sensors, outputs,
              work):  # pragma: no cover - compiled
    """One tick of the invariant EKF (see the module docstring); returns the fault flags.

    The groups are :func:`wbc.estimation.state_estimator_kernels._estimate`'s, with the
    parameter record holding ``InvariantEkfConfig``'s fields, ``filter_state`` the
    :class:`InvariantArrays` and ``work`` a record of :data:`WORK_SHAPES`: the tick
    allocates nothing.
    """
    p, w = params[0], work[0]
    x, P = filter_state.x, filter_state.P
    sigma_k, sigma_pos = p.kinematics_noise_rad, p.foot_position_noise_m
    sigma_vel, sigma_h = p.foot_velocity_noise_m_s, p.foot_height_noise_m
    swing_scale, min_weight, radius = p.swing_noise_scale, p.min_contact_weight, p.foot_radius_m
    weight, imu_offset = outputs.contact, legs.imu_offset
    foot_position, foot_jacobian = legs.foot_position, legs.foot_jacobian
    gyro_in, accel_in = sample.gyroscope, sample.accelerometer
    flags, dt, new, _quaternion_ok, gyro_ok, accel_ok, joints_ok = check_sample(
        sample, sensors.clock, p.control_period_s, p.quaternion_tolerance)
    rotation, omega, accel, turned = w.rotation, w.omega, w.accel, w.turned
    relative, velocity, rolling = w.relative, w.velocity, w.rolling
    blocks, step, product = w.blocks, w.step, w.product
    HP, S, innovation, body, kin = w.HP, w.S, w.innovation, w.body, w.kin
    height_row = w.height_row
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
    flags |= legs_and_contacts(joints_ok, new, dt, sample, schedule, p, legs, sensors, outputs,
                               w.legs)
    # --- prediction: the covariance on the unpropagated mean, then the mean
    _transition_blocks(rotation, x, dt, blocks)
    _propagate_covariance(P, blocks)
    _add_process_noise(P, x, p, weight, dt)
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
    foot_motion(rotation, omega, outputs.joint_dq, imu_offset, legs, radius, relative,
                velocity, rolling, w)
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
            _correct(x, P, HP, S, innovation, w)
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
                _correct(x, P, HP, S, innovation, w)
                quat_rotation(quat, rotation)
            if sigma_h > 0.0:
                # The foot centre's height r on a flat floor: d_z - r = 0. Not invariant:
                # the error's z-part is e_z . (xi_d - d^ xi_R), h = (d_y, -d_x, 0) on R.
                dx, dy = x[f], x[f + 1]
                for c in range(_DIM):
                    height_row[c] = dy * P[_R, c] - dx * P[_R + 1, c] + P[e + 2, c]
                variance = (dy * height_row[_R] - dx * height_row[_R + 1] + height_row[e + 2]
                            + scale * sigma_h * sigma_h)
                _correct_scalar(x, P, height_row, variance, radius - x[f + 2], w)
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
                  x[_VEL + 1], x[_VEL + 2], imu_offset, outputs, w)
    account_trust(flags, dt, sensors.clock)
    return flags


@numba.njit(cache=True)
def _estimate_from_header(header, readings, schedule, params, legs, filter_state, sensors,
                          outputs, work):  # pragma: no cover - compiled
    """:func:`_estimate` on the sample of ``header`` and ``readings``
    (:func:`~wbc.estimation.shared_kernels.sample_of`): the invariant EKF's tick as one compiled
    call whose arrays are read from a table of addresses
    (:class:`wbc.core.compiled_program.CompiledProgram`), the sample's scalars from ``header``."""
    return _estimate(sample_of(header, readings), schedule, params, legs, filter_state,
                     sensors, outputs, work)


@numba.njit(cache=True)
def _start(quat_in, q_in, params, legs, filter_state, base_x, base_y, keep_yaw,
           work):  # pragma: no cover - compiled
    """Start on four loaded feet, at rest, where :func:`start_pose` puts the base and the
    feet, biases 0, and the priors' covariance; the groups are :func:`_estimate`'s."""
    p, w = params[0], work[0]
    x, P = filter_state.x, filter_state.P
    sigma_pos, tilt = p.foot_position_noise_m, p.initial_tilt_rad
    gyro_bias, accel_bias = p.initial_gyro_bias_rad_s, p.initial_accel_bias_m_s2
    x[:] = 0.0
    start_pose(quat_in, q_in, keep_yaw, base_x, base_y, p.foot_radius_m, legs, w.align,
               x[_QUAT:_QUAT + 4], x[_POS:_POS + 3], x[_FEET:_FEET + 12].reshape((4, 3)), w)
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
    hat = w.hat  # p^
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
