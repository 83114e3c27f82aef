"""The control tick's task terms and QP assembly, fused in one compiled function.

At this size (31 variables, 50 rows) a NumPy assembly spends its time in Python overhead,
about 1 to 3 microseconds per small array operation, not in arithmetic. numba compiles the
same arithmetic to one machine-code function, called once per tick. The formulas are those
of the task classes in :mod:`tasks` (the reference, tested against finite differences);
``tests/test_qp_kernel.py`` checks that this function and the task classes agree.

Variable layout ``x = [qdd (18), f (4 x 3), s]``; row layout: floating-base dynamics (6),
stance contacts (12), torque limits (12), friction (16), support polygon (4).
"""

from __future__ import annotations

import numba
import numpy as np

NV, NJ, NC = 18, 12, 4
F0 = NV                # first force variable
S = NV + 3 * NC        # support-polygon slack
N = S + 1              # variables
DYN, CON, TAU, FRIC, SUP = 0, 6, 18, 30, 46
M_ROWS = 50
INF = 1e30
#: Velocity columns moving each foot: the floating base and the leg's three joints.
LEG_COLUMNS = np.array([[0, 1, 2, 3, 4, 5, 6 + 3 * i, 7 + 3 * i, 8 + 3 * i] for i in range(NC)])


@numba.njit(cache=True)
def log3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (the inverse of Rodrigues' formula)."""
    cos = min(1.0, max(-1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    # atan2 stays accurate near 0 and pi, where arccos of the trace does not.
    angle = np.arctan2(0.5 * np.sqrt(w @ w), cos)
    if angle < 1e-6:
        return 0.5 * w
    if np.pi - angle < 1e-6:  # at pi the antisymmetric part vanishes: use the symmetric
        axis = np.sqrt(np.maximum(0.0, (np.diag(R) - cos) / (1.0 - cos)))
        k = np.argmax(axis)
        for i in range(3):
            if i != k:
                axis[i] = np.copysign(axis[i], R[k, i] + R[i, k])
        if axis @ w < 0.0:  # what is left of the antisymmetric part gives the sign
            axis = -axis
        return angle * axis / np.linalg.norm(axis)
    return angle / (2.0 * np.sin(angle)) * w


@numba.njit(cache=True)
def add_least_squares(H, f, J, residual, weight):
    """``H += w J^T J`` and ``f += w J^T residual`` on the leading block, in place."""
    rows, cols = J.shape
    for i in range(cols):
        s = 0.0
        for r in range(rows):
            s += J[r, i] * residual[r]
        f[i] += weight * s
        for j in range(i, cols):
            s = 0.0
            for r in range(rows):
                s += J[r, i] * J[r, j]
            H[i, j] += weight * s
            if j != i:
                H[j, i] += weight * s


@numba.njit(cache=True)
def assemble(M, h, J, Jcom, com, vcom, acom, R, q, v,
             foot_pos, foot_acc, stance, radius, contact_kd,
             com_ref, com_gains, R_target, base_ref, base_gains, base_error,
             posture_ref, posture_gains, posture_weights,
             foot_ref, foot_gains,
             normals, offsets, n_edges, omega,
             tau_max, q_low, q_high, v_max, horizon,
             h_const, rate_weights, x_prev, tau_prev, torque_rate_weight,
             H, f, A, lower, upper, lb, ub, jc, errors, work_ms, work_foot_jac):
    """Fill the QP (``H, f, A, lower, upper`` and the joint rows of ``lb, ub``) for one tick.

    Args:
        M: Mass matrix (upper triangle used). h: nonlinear effects. J: joint Jacobians in
            the world frame (``data.J``). Jcom, com, vcom, acom: centre-of-mass terms
            (``acom`` at zero acceleration). R: base rotation. q, v: state.
        foot_pos (4, 3), foot_acc (4, 6): foot frame positions and classical accelerations
            (linear, angular; world axes) at zero joint acceleration.
        stance (4,): stance flags. radius: foot sphere radius. contact_kd: contact damping.
        com_ref (3, 3): target position, velocity, feed-forward. com_gains: kp, kd, weight.
        R_target: base orientation target; base_ref (3, 3): its target angular velocity
            and feed-forward in rows 1 and 2 (base frame); base_gains: kp, kd, weight;
            base_error (3,): written with the orientation error (for integral action).
        posture_ref (3, 12), posture_gains, posture_weights (12): same for the joints.
        foot_ref (4, 3, 3), foot_gains (4, 3): same per foot (used for swing feet).
        normals (4, 2), offsets (4,), n_edges, omega: support polygon barrier.
        tau_max, q_low, q_high, v_max, horizon: limits.
        h_const, rate_weights (30,), x_prev (30,): constant cost and smoothing.
        tau_prev (12,), torque_rate_weight: cost ``w |tau(x) - tau_prev|^2`` on the torque
            change from the previous tick, ``tau(x) = S x + h_a`` (S: the torque rows of A).
        H, f, A, lower, upper, lb, ub: the QP, written in place.
        jc (12, 18): scratch for the rolling-contact Jacobians (they end up in ``A``).
        errors (7,): written with error norms: com, base, posture, then the four feet.
        work_ms (18, 18), work_foot_jac (4, 6, 18): scratch space, allocated once by the
            caller (no allocation in the tick).
    """
    # Symmetric mass matrix from its upper triangle.
    Ms = work_ms
    for i in range(NV):
        for j in range(i, NV):
            Ms[i, j] = M[i, j]
            Ms[j, i] = M[i, j]

    # Foot Jacobians (world-aligned, at the frame origin) from the joint Jacobians.
    foot_jac = work_foot_jac
    foot_jac[:, :, :] = 0.0
    for i in range(NC):
        p = foot_pos[i]
        for c in LEG_COLUMNS[i]:
            wx, wy, wz = J[3, c], J[4, c], J[5, c]
            foot_jac[i, 0, c] = J[0, c] + wy * p[2] - wz * p[1]
            foot_jac[i, 1, c] = J[1, c] + wz * p[0] - wx * p[2]
            foot_jac[i, 2, c] = J[2, c] + wx * p[1] - wy * p[0]
            foot_jac[i, 3, c] = wx
            foot_jac[i, 4, c] = wy
            foot_jac[i, 5, c] = wz

    # Rolling contact points: J = J_lin - [d]x J_ang, d = (0, 0, -r).
    for i in range(NC):
        for k in range(NV):
            jc[3 * i, k] = foot_jac[i, 0, k] - radius * foot_jac[i, 4, k]
            jc[3 * i + 1, k] = foot_jac[i, 1, k] + radius * foot_jac[i, 3, k]
            jc[3 * i + 2, k] = foot_jac[i, 2, k]
        drift0 = foot_acc[i, 0] - radius * foot_acc[i, 4]
        drift1 = foot_acc[i, 1] + radius * foot_acc[i, 3]
        drift2 = foot_acc[i, 2]
        for a, drift in ((0, drift0), (1, drift1), (2, drift2)):
            row = 3 * i + a
            vel = 0.0
            for k in range(NV):
                vel += jc[row, k] * v[k]
            rhs = -contact_kd * vel - drift
            if stance[i]:
                lower[CON + row] = rhs
                upper[CON + row] = rhs
            else:
                lower[CON + row] = -INF
                upper[CON + row] = INF

    # Equations of motion (floating base), stance contacts, torque limits.
    A[DYN:DYN + 6, :NV] = Ms[:6]
    A[TAU:TAU + NJ, :NV] = Ms[6:]
    for r in range(3 * NC):
        for k in range(6):
            A[DYN + k, F0 + r] = -jc[r, k]
        for k in range(NJ):
            A[TAU + k, F0 + r] = -jc[r, 6 + k]
    for k in range(6):
        lower[DYN + k] = -h[k]
        upper[DYN + k] = -h[k]
    A[CON:CON + 3 * NC, :NV] = jc
    for k in range(NJ):
        lower[TAU + k] = -tau_max[k] - h[6 + k]
        upper[TAU + k] = tau_max[k] - h[6 + k]

    # Centre of mass inside the support polygon: a soft, critically damped barrier.
    for e in range(4):
        row = SUP + e
        if e < n_edges:
            nx, ny = normals[e, 0], normals[e, 1]
            for k in range(NV):
                A[row, k] = nx * Jcom[0, k] + ny * Jcom[1, k]
            distance = nx * com[0] + ny * com[1] - offsets[e]
            lower[row] = -(nx * (acom[0] + 2.0 * omega * vcom[0])
                           + ny * (acom[1] + 2.0 * omega * vcom[1])) - omega * omega * distance
            upper[row] = INF
        else:
            A[row, :NV] = 0.0
            lower[row] = -INF
            upper[row] = INF

    # Joint limits as acceleration bounds over the horizon; velocity limits.
    for k in range(NJ):
        qj, vj = q[7 + k], v[6 + k]
        hi = min(2.0 * (q_high[k] - qj - vj * horizon) / (horizon * horizon),
                 (v_max[k] - vj) / horizon)
        lo = max(2.0 * (q_low[k] - qj - vj * horizon) / (horizon * horizon),
                 (-v_max[k] - vj) / horizon)
        lb[6 + k] = min(lo, hi)
        ub[6 + k] = hi

    # Cost.
    H[:, :] = h_const
    f[:] = 0.0
    # Centre of mass: weight * |Jcom qdd + acom - a_des|^2.
    kp, kd, w = com_gains[0], com_gains[1], com_gains[2]
    residual = np.empty(3)
    total = 0.0
    for a in range(3):
        e = com_ref[0, a] - com[a]
        residual[a] = acom[a] - (kp * e + kd * (com_ref[1, a] - vcom[a]) + com_ref[2, a])
        total += e * e
    add_least_squares(H, f, Jcom, residual, w)
    errors[0] = np.sqrt(total)
    # Base orientation: the Jacobian selects v[3:6], the drift is zero.
    kp, kd, w = base_gains[0], base_gains[1], base_gains[2]
    err = log3(R.T @ R_target)
    base_error[:] = err
    for k in range(3):
        H[3 + k, 3 + k] += w
        f[3 + k] -= w * (kp * err[k] + kd * (base_ref[1, k] - v[3 + k]) + base_ref[2, k])
    errors[1] = np.sqrt(np.sum(err * err))
    # Posture: the Jacobian selects the joints.
    kp, kd, w = posture_gains[0], posture_gains[1], posture_gains[2]
    total = 0.0
    for k in range(NJ):
        e = posture_ref[0, k] - q[7 + k]
        wk = w * posture_weights[k]
        H[6 + k, 6 + k] += wk
        f[6 + k] -= wk * (kp * e + kd * (posture_ref[1, k] - v[6 + k]) + posture_ref[2, k])
        total += e * e
    errors[2] = np.sqrt(total)
    # Swing feet: position tasks on the foot frames.
    for i in range(NC):
        errors[3 + i] = 0.0
        if stance[i]:
            continue
        kp, kd, w = foot_gains[i, 0], foot_gains[i, 1], foot_gains[i, 2]
        Jf = foot_jac[i, :3]
        total = 0.0
        for a in range(3):
            e = foot_ref[i, 0, a] - foot_pos[i, a]
            vel = 0.0
            for k in range(NV):
                vel += Jf[a, k] * v[k]
            residual[a] = foot_acc[i, a] - (kp * e + kd * (foot_ref[i, 1, a] - vel)
                                            + foot_ref[i, 2, a])
            total += e * e
        add_least_squares(H, f, Jf, residual, w)
        errors[3 + i] = np.sqrt(total)
    # Smoothness: a pull towards the previous tick's solution, and on the torque change.
    for k in range(S):
        f[k] -= rate_weights[k] * x_prev[k]
    if torque_rate_weight > 0.0:
        offset = np.empty(NJ)
        for k in range(NJ):
            offset[k] = h[6 + k] - tau_prev[k]
        add_least_squares(H, f, A[TAU:TAU + NJ, :S], offset, torque_rate_weight)
