"""The invariant EKF's algebra on SE_{2+4}(3): the right-invariant error's transition and
process noise, and corrections applied on the group.

The layout of the mean and of the error below is shared with the tick
(:mod:`wbc.estimation.invariant_ekf_kernels`) and the class
(:mod:`wbc.estimation.invariant_ekf`). Row-major throughout, nothing allocated.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.quaternion_kernels import quat_exp, quat_multiply, quat_normalize, quat_rotation

# The error state's blocks (27): rotation, IMU velocity, IMU position, feet 0..3, gyro bias,
# accelerometer bias.
_R, _V, _P, _D, _BG, _BA = 0, 3, 6, 9, 21, 24
_DIM = 27
# The mean ``x``: orientation (w, x, y, z), velocity, position, feet, biases, and the last
# good gyroscope and accelerometer readings (reused when a reading is missing or bad).
_QUAT, _VEL, _POS, _FEET, _GBIAS, _ABIAS, _GYRO, _ACCEL = 0, 4, 7, 10, 22, 25, 28, 31
_X_SIZE = 34
#: The transition matrix's off-identity 3 x 3 blocks ``(row block, column block)``, in the
#: order :func:`_transition_blocks` fills them: no block reads a row block that an earlier
#: one wrote, so ``(I + F) P`` can be computed in place, row block by row block.
_BLOCK_ROWS = np.array([_P, _P, _P, _P, _V, _V, _V, _R, _D, _D + 3, _D + 6, _D + 9])
_BLOCK_COLS = np.array([_R, _V, _BG, _BA, _R, _BG, _BA, _BG, _BG, _BG, _BG, _BG])
_BLOCKS = 12
#: The corrections' work arrays, by name and shape (fields of the tick's work record): the
#: innovation covariance's inverse, the gain's transpose, the error step, and the group
#: update's rotation step, its product, its matrix and a vector.
CORRECTION_WORK: dict[str, tuple[int, ...]] = {
    "correction_inverse": (3, 3), "correction_gain": (3, _DIM), "correction_delta": (_DIM,),
    "correction_step": (4,), "correction_product": (4,), "correction_rotation": (3, 3),
    "correction_vector": (3,),
}


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
    g = GRAVITY_M_S2
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
def _add_process_noise(P, x, params, weight, dt):  # pragma: no cover - compiled
    """``P += Ad_X Q Ad_X^T dt``: the IMU's and the feet's noise in the right-invariant
    error (the gyroscope's noise reaches every translation ``x`` as ``x^``); ``params``:
    the parameter record (its noise densities and ``min_contact_weight``, by name)."""
    gyro2 = params.gyroscope_noise * params.gyroscope_noise * dt
    accel2 = params.accelerometer_noise * params.accelerometer_noise * dt
    min_weight = params.min_contact_weight
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
    contact2 = params.contact_noise * params.contact_noise * dt
    gbias2 = params.gyro_bias_noise * params.gyro_bias_noise * dt
    abias2 = params.accel_bias_noise * params.accel_bias_noise * dt
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

    ``work``: the work record (its ``correction_step``, ``_product``, ``_rotation`` and
    ``_vector`` are scratch).
    """
    step, product = work.correction_step, work.correction_product
    dR, vec = work.correction_rotation, work.correction_vector
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
    loop runs along a row of 27. ``work``: the work record (:data:`CORRECTION_WORK`)."""
    inverse = work.correction_inverse
    gain = work.correction_gain  # K^T = S^-1 H P
    delta = work.correction_delta
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
    _apply_correction(x, delta, work)


@numba.njit(cache=True)
def _correct_scalar(x, P, hP, variance, innovation, work):  # pragma: no cover - compiled
    """A scalar Kalman correction given ``hP = h^T P`` (27,) and ``h^T P h + noise``;
    ``work``: the work record (:data:`CORRECTION_WORK`)."""
    delta = work.correction_delta
    if not variance > 0.0:
        return
    for r in range(_DIM):
        delta[r] = hP[r] / variance * innovation
    for r in range(_DIM):
        k = hP[r] / variance
        row = P[r]
        for c in range(_DIM):
            row[c] -= k * hP[c]
    _apply_correction(x, delta, work)
