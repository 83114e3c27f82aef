"""A contact-aided invariant EKF for the GO2's floating base: the linear filter's alternative.

:class:`InvariantEkf` has :class:`wbc.estimation.state_estimator.StateEstimator`'s API (``reset``,
``update``, ``estimate``, ``describe``...) and shares its sample checks, trust accounting,
contact weights, foot motion, outputs and fault text, so the two can be swapped in the
control loop and compared by measurement. The filter itself is the right-invariant EKF of
Hartley et al., "Contact-aided invariant extended Kalman filtering for robot state
estimation" (IJRR 2020), with the IMU biases appended ("imperfect InEKF"):

- **State**: the base orientation ``R``, the velocity ``v`` and position ``p`` of the IMU
  site (the URDF's ``imu`` frame, parallel to the base) and the four foot sphere centres
  ``d_i``, one element of SE_{2+4}(3); then the gyroscope and accelerometer biases. The
  error is right-invariant (27 numbers: rotation, v, p, four feet, two biases) and its
  covariance a dense 27 x 27 matrix.
- **Prediction**: the gyroscope and accelerometer less their estimated biases (gravity
  9.81 m/s^2 down). A stance foot's centre moves as its sphere rolls (``omega_foot x (0,
  0, r)``, :func:`wbc.estimation.state_estimator.foot_motion`): a known world-frame input to ``d_i``
  (its first-order effect on the error, ``u x`` on the rotation, is millimetres per second
  against gravity's 9.81 m/s^2 and is left out of the Jacobian). A foot whose contact
  weight is below ``min_contact_weight`` is re-initialised from the kinematics every tick:
  ``d_i = p + R y_i`` and, as the invariant error makes exact, its covariance rows are the
  position's (plus the kinematic noise).
- **Correction**: each contact foot's position in the body frame, ``y_i = R^T (d_i - p)``
  (the group's right-invariant observation: a constant Jacobian), noise
  ``kinematics_noise_rad^2 J J^T + foot_position_noise_m^2 I`` grown ``swing_noise_scale ^
  (1 - weight)`` times as the foot is unloaded, one foot at a time. Two measurements of the
  linear filter are optional here (0 turns them off): the IMU velocity from a rolling stance
  foot (``foot_velocity_noise_m_s``, a right-invariant observation too) and a stance foot's
  height on a flat floor (``foot_height_noise_m``, not invariant: its Jacobian has the foot
  position in it).

How it differs from the linear filter: the orientation is the filter's own, from the
gyroscope, gravity and the stance feet; the IMU's quaternion is only read by :meth:`reset`
(yaw 0, roll and pitch from it), so a broken quaternion never matters and the IMU's yaw
drift does not enter. Roll and pitch come from gravity through the accelerometer (which
cannot tell a small tilt from a horizontal accelerometer bias: the priors share it); the
gyroscope bias is learnt on all three axes while feet stand still (a yaw rate moves the
feet in the body frame), and the yaw itself drifts only as the feet let it. The position,
velocity, orientation and biases are one filter (the linear filter splits them into three
6-state ones, with the orientation given): a 27 x 27 covariance, propagated and corrected
with row operations only, about 6 us a tick compiled (the linear filter's kernel: 3.5 us),
with no allocation. Fault flags, contact fusion and outputs are the linear filter's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numba
import numpy as np

from wbc.core.quaternion_kernels import (
    quat_exp,
    quat_multiply,
    quat_normalize,
    quat_rotation,
    quat_yaw,
)
from wbc.core.validation import known_fields_only
from wbc.estimation.state_estimator import (
    EstimatorBase,
    SensorTrustConfig,
    account_trust,
    check_sample,
    foot_motion,
    legs_and_contacts,
    write_outputs,
)
from wbc.model.description import Go2Description
from wbc.model.leg_kinematics import leg_kinematics

_GRAVITY = 9.81

# The error state's blocks (27): rotation, IMU velocity, IMU position, feet 0..3, gyro bias,
# accelerometer bias.
_R, _V, _P, _D, _BG, _BA = 0, 3, 6, 9, 21, 24
_DIM = 27
# The mean ``x``: orientation (w, x, y, z), velocity, position, feet, biases, and the last
# good gyroscope and accelerometer readings (reused when a reading is missing or bad).
_QUAT, _VEL, _POS, _FEET, _GBIAS, _ABIAS, _GYRO, _ACCEL = 0, 4, 7, 10, 22, 25, 28, 31
_X_SIZE = 34
#: Scratch space of the tick's kernel (see :func:`_estimate`).
_WORK_SIZE = 497
#: The transition matrix's off-identity 3 x 3 blocks ``(row block, column block)``, in the
#: order :func:`_transition_blocks` fills them: no block reads a row block that an earlier
#: one wrote, so ``(I + F) P`` can be computed in place, row block by row block.
_BLOCK_ROWS = np.array([_P, _P, _P, _P, _V, _V, _V, _R, _D, _D + 3, _D + 6, _D + 9])
_BLOCK_COLS = np.array([_R, _V, _BG, _BA, _R, _BG, _BA, _BG, _BG, _BG, _BG, _BG])
_BLOCKS = 12


@known_fields_only("estimator parameter")
@dataclass(frozen=True)
class InvariantEkfConfig(SensorTrustConfig):
    """Every number of the invariant EKF, validated (an error names the field and its range).

    The noise densities are continuous-time: a tick of ``dt`` seconds adds ``noise^2 dt`` to
    the covariance. They are tuning numbers (they take up what the models miss), not the
    sensors' datasheet values. They start from what go2_odometry's InEKF uses on a GO2
    (gyroscope 0.01, accelerometer 0.1, bias walks 1e-5 and 1e-4, contact 1e-3, kinematics
    1e-3 rad). Measured in closed loop (high fives, three sensor seeds; velocity error RMS,
    largest roll or pitch error): those give 0.74 mm/s and 0.16 deg; a gyroscope of 0.003
    and an accelerometer-bias prior of 0.2 m/s^2 (a MEMS offset of about 20 mg) give 0.52
    mm/s and 0.055 deg; the other noises change nothing measurable within a factor of 3.
    The gyroscope-bias prior of 0.01 rad/s (a MEMS offset of about 0.5 deg/s) costs 0.02
    deg of that on the simulated GO2's small biases, but learns a 3e-3 rad/s bias in 5 s
    rather than over 30 s (1e-3 rad/s: the estimate tilted 0.35 deg meanwhile), and with
    larger biases in closed loop (5e-3 rad/s, 0.1 m/s^2) kept the raised foot within 1.9
    mm RMS of its target instead of 4.9.

    Attributes:
        gyroscope_noise: Gyroscope noise density [rad/s/sqrt(Hz)].
        accelerometer_noise: Accelerometer noise density [m/s^2/sqrt(Hz)].
        gyro_bias_noise: Random walk of the gyroscope bias [rad/s/sqrt(s)].
        accel_bias_noise: Random walk of the accelerometer bias [m/s^2/sqrt(s)].
        contact_noise: Random walk of a stance foot's centre [m/sqrt(s)] (slip, and the
            rolling the model misses).
        kinematics_noise_rad: Joint-angle noise [rad] of a foot's kinematic position (its
            covariance ``kinematics_noise_rad^2 J J^T``).
        foot_velocity_noise_m_s: Noise [m/s] of the IMU velocity from a rolling stance
            foot (0: not measured).
        foot_height_noise_m: Noise [m] of a stance foot's height above a flat floor at
            z = 0 (0: not measured).
        initial_tilt_rad: Prior standard deviation of roll and pitch at :meth:`reset` [rad]
            (they come from the IMU's attitude filter then).
        initial_gyro_bias_rad_s: Prior standard deviation of the gyroscope bias [rad/s].
        initial_accel_bias_m_s2: Prior standard deviation of the accelerometer bias
            [m/s^2].

    The shared ones are :class:`wbc.estimation.state_estimator.SensorTrustConfig`'s; here
        ``quaternion_timeout_s`` is unused: the orientation never depends on the IMU's
        quaternion after :meth:`InvariantEkf.reset`.
    """

    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "gyroscope_noise": (1e-9, 10.0), "accelerometer_noise": (1e-9, 100.0),
        "gyro_bias_noise": (1e-12, 1.0), "accel_bias_noise": (1e-12, 10.0),
        "contact_noise": (1e-9, 10.0), "kinematics_noise_rad": (0.0, 1.0),
        "foot_velocity_noise_m_s": (0.0, 10.0), "foot_height_noise_m": (0.0, 1.0),
        "initial_tilt_rad": (1e-9, 1.0), "initial_gyro_bias_rad_s": (1e-9, 1.0),
        "initial_accel_bias_m_s2": (1e-9, 10.0),
    }
    _PARAMS: ClassVar[tuple[str, ...]] = (
        "gyroscope_noise", "accelerometer_noise", "gyro_bias_noise", "accel_bias_noise",
        "contact_noise", "kinematics_noise_rad", "foot_position_noise_m",
        "foot_velocity_noise_m_s", "foot_height_noise_m", "swing_noise_scale",
        "min_contact_weight", "foot_radius_m", "quaternion_tolerance", "initial_tilt_rad",
        "initial_gyro_bias_rad_s", "initial_accel_bias_m_s2")

    gyroscope_noise: float = 0.003
    accelerometer_noise: float = 0.1
    gyro_bias_noise: float = 1e-5
    accel_bias_noise: float = 1e-4
    contact_noise: float = 1e-3
    kinematics_noise_rad: float = 1e-3
    foot_velocity_noise_m_s: float = 0.0
    foot_height_noise_m: float = 0.0
    initial_tilt_rad: float = 0.01
    initial_gyro_bias_rad_s: float = 0.01
    initial_accel_bias_m_s2: float = 0.2


# ----------------------------------------------------------------------------- the kernel


@numba.njit(cache=True)
def _skew_times(a, b, out):  # pragma: no cover - compiled
    """``out = a x b`` (3,)."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@numba.njit(cache=True)
def _transition_blocks(rotation, x, dt, blocks):  # pragma: no cover - compiled
    """The right-invariant error's transition matrix ``I + F`` over ``dt`` [s], to first
    order: ``blocks`` (12, 3, 3) gets F's blocks at :data:`_BLOCK_ROWS`/:data:`_BLOCK_COLS`.

    Gravity turns a rotation error into velocity and position errors; the biases enter
    through the rotation (``-R``) and, as the right-invariant error measures every
    translation from the world's origin, through ``-(x)^ R`` for each translation ``x``.
    """
    g = _GRAVITY
    blocks[:, :, :] = 0.0
    # (p, R) = g^ dt^2 / 2 and (v, R) = g^ dt, g = (0, 0, -g): g^ = [[0, g, 0], [-g, 0, 0], 0].
    blocks[0, 0, 1] = 0.5 * g * dt * dt
    blocks[0, 1, 0] = -0.5 * g * dt * dt
    blocks[4, 0, 1] = g * dt
    blocks[4, 1, 0] = -g * dt
    for k in range(3):
        blocks[1, k, k] = dt
    for r in range(3):
        for c in range(3):
            blocks[3, r, c] = -0.5 * rotation[r, c] * dt * dt
            blocks[6, r, c] = -rotation[r, c] * dt
            blocks[7, r, c] = -rotation[r, c] * dt
    # (x, bg) = -(x)^ R dt for x = p, v, d_0..d_3.
    for b in range(6):
        block = (2, 5, 8, 9, 10, 11)[b]
        start = _POS if b == 0 else (_VEL if b == 1 else _FEET + 3 * (b - 2))
        x0, x1, x2 = x[start], x[start + 1], x[start + 2]
        for c in range(3):
            r0, r1, r2 = rotation[0, c], rotation[1, c], rotation[2, c]
            blocks[block, 0, c] = -(x1 * r2 - x2 * r1) * dt
            blocks[block, 1, c] = -(x2 * r0 - x0 * r2) * dt
            blocks[block, 2, c] = -(x0 * r1 - x1 * r0) * dt


@numba.njit(cache=True)
def _transition_rows(P, blocks):  # pragma: no cover - compiled
    """``P <- (I + F) P`` in place, row block by row block (see :data:`_BLOCK_ROWS`)."""
    n = P.shape[1]
    for b in range(_BLOCKS):
        row, col, B = _BLOCK_ROWS[b], _BLOCK_COLS[b], blocks[b]
        for r in range(3):
            b0, b1, b2 = B[r, 0], B[r, 1], B[r, 2]
            if b0 == 0.0 and b1 == 0.0 and b2 == 0.0:
                continue
            target = P[row + r]
            for c in range(n):
                target[c] += b0 * P[col, c] + b1 * P[col + 1, c] + b2 * P[col + 2, c]


@numba.njit(cache=True)
def _propagate_covariance(P, blocks):  # pragma: no cover - compiled
    """``P <- (I + F) P (I + F)^T`` for a symmetric P, as ``(I + F) ((I + F) P)^T``: two
    passes of row operations (contiguous, vectorised) and a transposition in place."""
    _transition_rows(P, blocks)
    n = P.shape[0]
    for r in range(n):
        for c in range(r):
            P[r, c], P[c, r] = P[c, r], P[r, c]
    _transition_rows(P, blocks)


@numba.njit(cache=True)
def _add_process_noise(P, x, params, weight, min_weight, dt):  # pragma: no cover - compiled
    """``P += Ad_X Q Ad_X^T dt``: the IMU's and the feet's noise in the right-invariant
    error (the gyroscope's noise reaches every translation ``x`` as ``x^``)."""
    gyro2 = params[0] * params[0] * dt
    accel2 = params[1] * params[1] * dt
    # Blocks 0 (rotation), 1 (v), 2 (p), 3..6 (feet): the gyroscope's term W_a W_b^T with
    # W_R = I and W_x = x^.
    for a in range(7):
        sa = _VEL if a == 1 else (_POS if a == 2 else _FEET + 3 * (a - 3))
        ea = 3 * a
        for b in range(7):
            sb = _VEL if b == 1 else (_POS if b == 2 else _FEET + 3 * (b - 3))
            eb = 3 * b
            if a == 0 and b == 0:
                for k in range(3):
                    P[k, k] += gyro2
            elif a == 0:  # -(x_b)^
                xb0, xb1, xb2 = x[sb], x[sb + 1], x[sb + 2]
                P[0, eb + 1] += gyro2 * xb2
                P[0, eb + 2] -= gyro2 * xb1
                P[1, eb + 0] -= gyro2 * xb2
                P[1, eb + 2] += gyro2 * xb0
                P[2, eb + 0] += gyro2 * xb1
                P[2, eb + 1] -= gyro2 * xb0
            elif b == 0:  # (x_a)^
                xa0, xa1, xa2 = x[sa], x[sa + 1], x[sa + 2]
                P[ea + 0, 1] -= gyro2 * xa2
                P[ea + 0, 2] += gyro2 * xa1
                P[ea + 1, 0] += gyro2 * xa2
                P[ea + 1, 2] -= gyro2 * xa0
                P[ea + 2, 0] -= gyro2 * xa1
                P[ea + 2, 1] += gyro2 * xa0
            else:  # -(x_a)^ (x_b)^ = (x_a . x_b) I - x_b x_a^T
                dot = x[sa] * x[sb] + x[sa + 1] * x[sb + 1] + x[sa + 2] * x[sb + 2]
                for r in range(3):
                    for c in range(3):
                        P[ea + r, eb + c] += gyro2 * ((dot if r == c else 0.0)
                                                      - x[sb + r] * x[sa + c])
    contact2 = params[4] * params[4] * dt
    gbias2 = params[2] * params[2] * dt
    abias2 = params[3] * params[3] * dt
    for k in range(3):
        P[_V + k, _V + k] += accel2
        P[_BG + k, _BG + k] += gbias2
        P[_BA + k, _BA + k] += abias2
        for i in range(4):
            if weight[i] >= min_weight:
                P[_D + 3 * i + k, _D + 3 * i + k] += contact2


@numba.njit(cache=True)
def _apply_correction(x, delta, work):  # pragma: no cover - compiled
    """``X <- Exp(delta) X`` on SE_{2+4}(3) (right-invariant update), biases ``+= delta``.

    ``work`` (21,): scratch for the rotation step, its matrix and the left Jacobian.
    """
    step, product = work[0:4], work[4:8]
    dR = work[8:17].reshape((3, 3))
    vec = work[17:20]
    phi0, phi1, phi2 = delta[0], delta[1], delta[2]
    quat_exp(phi0, phi1, phi2, step)
    quat_rotation(step, dR)
    quat_multiply(step, x[_QUAT:_QUAT + 4], product)
    quat_normalize(product)
    x[_QUAT:_QUAT + 4] = product
    # The left Jacobian of SO(3): J = I + a phi^ + b phi^2.
    angle2 = phi0 * phi0 + phi1 * phi1 + phi2 * phi2
    if angle2 > 1e-8:
        angle = math.sqrt(angle2)
        a = (1.0 - math.cos(angle)) / angle2
        b = (angle - math.sin(angle)) / (angle2 * angle)
    else:
        a = 0.5 - angle2 / 24.0
        b = 1.0 / 6.0 - angle2 / 120.0
    for s in range(6):  # v, p, feet: x <- dR x + J delta_x
        start = _VEL if s == 0 else (_POS if s == 1 else _FEET + 3 * (s - 2))
        e = 3 + 3 * s
        d0, d1, d2 = delta[e], delta[e + 1], delta[e + 2]
        c0 = phi1 * d2 - phi2 * d1  # phi x d
        c1 = phi2 * d0 - phi0 * d2
        c2 = phi0 * d1 - phi1 * d0
        cc0 = phi1 * c2 - phi2 * c1  # phi x (phi x d)
        cc1 = phi2 * c0 - phi0 * c2
        cc2 = phi0 * c1 - phi1 * c0
        for r in range(3):
            vec[r] = dR[r, 0] * x[start] + dR[r, 1] * x[start + 1] + dR[r, 2] * x[start + 2]
        x[start] = vec[0] + d0 + a * c0 + b * cc0
        x[start + 1] = vec[1] + d1 + a * c1 + b * cc1
        x[start + 2] = vec[2] + d2 + a * c2 + b * cc2
    for k in range(6):
        x[_GBIAS + k] += delta[_BG + k]


@numba.njit(cache=True)
def _correct(x, P, HP, S, innovation, work):  # pragma: no cover - compiled
    """A 3-D Kalman correction given ``HP = H P`` (3, 27), the innovation covariance ``S =
    H P H^T + noise`` (3, 3) and the innovation (3,); applies it to the mean
    (:func:`_apply_correction`) and ``P <- P - K H P``. Row-major throughout: every inner
    loop runs along a row of 27."""
    inverse = work[0:9].reshape((3, 3))
    gain = work[9:90].reshape((3, 27))  # K^T = S^-1 H P
    delta = work[90:117]
    # The inverse of the symmetric 3 x 3 innovation covariance, by cofactors.
    c00 = S[1, 1] * S[2, 2] - S[1, 2] * S[2, 1]
    c01 = S[0, 2] * S[2, 1] - S[0, 1] * S[2, 2]
    c02 = S[0, 1] * S[1, 2] - S[0, 2] * S[1, 1]
    det = S[0, 0] * c00 + S[1, 0] * c01 + S[2, 0] * c02
    if not det > 0.0:  # not positive definite: skip the measurement rather than diverge
        return
    inverse[0, 0] = c00 / det
    inverse[0, 1] = c01 / det
    inverse[0, 2] = c02 / det
    inverse[1, 1] = (S[0, 0] * S[2, 2] - S[0, 2] * S[2, 0]) / det
    inverse[1, 2] = (S[0, 2] * S[1, 0] - S[0, 0] * S[1, 2]) / det
    inverse[2, 2] = (S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]) / det
    inverse[1, 0] = inverse[0, 1]
    inverse[2, 0] = inverse[0, 2]
    inverse[2, 1] = inverse[1, 2]
    for k in range(3):
        i0, i1, i2 = inverse[k, 0], inverse[k, 1], inverse[k, 2]
        for c in range(_DIM):
            gain[k, c] = i0 * HP[0, c] + i1 * HP[1, c] + i2 * HP[2, c]
    z0, z1, z2 = innovation[0], innovation[1], innovation[2]
    for c in range(_DIM):
        delta[c] = gain[0, c] * z0 + gain[1, c] * z1 + gain[2, c] * z2
    for r in range(_DIM):
        k0, k1, k2 = gain[0, r], gain[1, r], gain[2, r]
        row = P[r]
        for c in range(_DIM):
            row[c] -= k0 * HP[0, c] + k1 * HP[1, c] + k2 * HP[2, c]
    _apply_correction(x, delta, work[117:138])


@numba.njit(cache=True)
def _correct_scalar(x, P, hP, variance, innovation, work):  # pragma: no cover - compiled
    """A scalar Kalman correction given ``hP = h^T P`` (27,) and ``h^T P h + noise``."""
    delta = work[0:27]
    if not variance > 0.0:
        return
    for r in range(_DIM):
        delta[r] = hP[r] / variance * innovation
    for r in range(_DIM):
        k = hP[r] / variance
        row = P[r]
        for c in range(_DIM):
            row[c] -= k * hP[c]
    _apply_correction(x, delta, work[27:48])


@numba.njit(cache=True)
def _estimate(fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, force_in,
              schedule, dt_nominal, params, imu_offset, rotations, translations, axes,
              foot_offsets, foot_position, foot_jacobian, foot_angular_jacobian, clock, x, P,
              foot_contact, foot_same_s, foot_good_s, foot_reason, foot_last, joint_q,
              joint_dq, q_out, v_out, weight, work):  # pragma: no cover - compiled
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
            accel[k] = _GRAVITY * rotation[2, k]
    flags |= legs_and_contacts(joints_ok, new, dt, q_in, dq_in, force_in, schedule, params,
                               rotations, translations, axes, foot_offsets, foot_position,
                               foot_jacobian, foot_angular_jacobian, legs_work, joint_q,
                               joint_dq, foot_contact, foot_same_s, foot_good_s, foot_reason,
                               foot_last, weight)
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
            a1 -= _GRAVITY
            a2 -= 0.5 * _GRAVITY
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
    """Start on four loaded feet, at rest: orientation from the IMU (yaw 0 unless
    ``keep_yaw``), height from the feet on the floor, the base at ``(base_x, base_y)``,
    biases 0, and the priors' covariance. ``work`` (57,): scratch."""
    sigma_pos, radius = params[6], params[11]
    tilt, gyro_bias, accel_bias = params[13], params[14], params[15]
    measured, align, quat = work[0:4], work[4:8], work[8:12]
    rotation = work[12:21].reshape((3, 3))
    legs_work = work[21:57].reshape((4, 3, 3))
    norm = math.sqrt(quat_in[0] ** 2 + quat_in[1] ** 2 + quat_in[2] ** 2 + quat_in[3] ** 2)
    for k in range(4):
        measured[k] = quat_in[k] / norm
    yaw = 0.0 if keep_yaw else quat_yaw(measured)
    align[0], align[1], align[2], align[3] = math.cos(-0.5 * yaw), 0.0, 0.0, math.sin(-0.5 * yaw)
    quat_multiply(align, measured, quat)
    quat_normalize(quat)
    quat_rotation(quat, rotation)
    leg_kinematics(q_in, rotations, translations, axes, foot_offsets, foot_position,
                   foot_jacobian, foot_angular_jacobian, legs_work)
    height = 0.0
    for i in range(4):
        height += radius - (rotation[2, 0] * foot_position[i, 0]
                            + rotation[2, 1] * foot_position[i, 1]
                            + rotation[2, 2] * foot_position[i, 2])
    height /= 4.0
    x[:] = 0.0
    x[_QUAT:_QUAT + 4] = quat
    for r in range(3):
        base = base_x if r == 0 else (base_y if r == 1 else height)
        x[_POS + r] = base + (rotation[r, 0] * imu_offset[0] + rotation[r, 1] * imu_offset[1]
                              + rotation[r, 2] * imu_offset[2])
        for i in range(4):
            x[_FEET + 3 * i + r] = base + (rotation[r, 0] * foot_position[i, 0]
                                           + rotation[r, 1] * foot_position[i, 1]
                                           + rotation[r, 2] * foot_position[i, 2])
    x[_ACCEL + 2] = _GRAVITY
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
    hat = rotation  # reused: p^
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


# ----------------------------------------------------------------------------- the class


class InvariantEkf(EstimatorBase):
    """The base's state from a GO2's sensors by a contact-aided invariant EKF (see the
    module docstring); the API of :class:`wbc.estimation.state_estimator.StateEstimator`.

    Args:
        config: Every number (defaults when ``None``); see :class:`InvariantEkfConfig`.
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of :class:`InvariantEkfConfig` to change.

    Example:
        >>> loop = ControlLoop.simulated(estimator=InvariantEkf())
        >>> estimator = InvariantEkf(control_period_s=2e-3)
        >>> estimator.reset(record)                       # four feet on the floor
        >>> estimate = estimator.update(record, loads)    # every tick
    """

    config_class = InvariantEkfConfig
    kernel = _estimate
    work_size = _WORK_SIZE
    quaternion_note = "not used after the start (the orientation is the filter's own)"
    config: InvariantEkfConfig

    def __init__(self, config: InvariantEkfConfig | None = None, *,
                 description: Go2Description | None = None, control_period_s: float = 1e-3,
                 **overrides: Any):
        super().__init__(config, description=description, control_period_s=control_period_s,
                         **overrides)
        self._x = np.zeros(_X_SIZE)
        self._x[_QUAT] = 1.0
        self._P = np.zeros((_DIM, _DIM))

    def _filter_arrays(self) -> tuple[np.ndarray, ...]:
        return self._x, self._P

    def _start_filter(self, quaternion: np.ndarray, joint_q: np.ndarray,
                      base_xy: tuple[float, float], keep_yaw: bool) -> None:
        legs = self.legs
        _start(quaternion, joint_q, self._params, legs.imu_offset, legs.rotations,
               legs.translations, legs.axes, legs.foot_offsets, legs.foot_position,
               legs.foot_jacobian, legs.foot_angular_jacobian, self._x, self._P, base_xy[0],
               base_xy[1], keep_yaw, self._work)

    @property
    def gyro_bias(self) -> np.ndarray:
        """The learnt gyroscope bias [rad/s] (a copy)."""
        return self._x[_GBIAS:_GBIAS + 3].copy()

    @property
    def accel_bias(self) -> np.ndarray:
        """The learnt accelerometer bias [m/s^2] (a copy)."""
        return self._x[_ABIAS:_ABIAS + 3].copy()

    @property
    def foot_positions(self) -> np.ndarray:
        """The filter's foot centres (4, 3) [m], estimator world frame (a copy)."""
        return self._x[_FEET:_FEET + 12].reshape(4, 3).copy()

    @property
    def covariance(self) -> np.ndarray:
        """The right-invariant error's covariance (27, 27) (a copy): rotation, IMU
        velocity, IMU position, feet FL, FR, RL, RR, gyroscope bias, accelerometer bias."""
        return self._P.copy()
