"""Compiled kernels of the built-in constraints: each writes its rows in one call, in place."""

from __future__ import annotations

import numba

INF = 1e30


@numba.njit(cache=True)
def equation_of_motion_rows(M, h, contact_jacobian, loaded, force_columns, first, A, lower,
                            upper, bound):
    """Rows ``first..`` of ``M qdd + h - J_c^T f``, bounded by ``[-bound - h, bound - h]``.

    With ``first = 0`` and a zero ``bound`` these are the floating base's equations of
    motion (equalities); with ``first = 6`` and the torque limits, the actuated joints'
    torques ``tau = M_a qdd + h_a - J_a^T f`` kept within their limits.
    """
    nv = M.shape[0]
    for r in range(A.shape[0]):
        g = first + r
        for k in range(nv):
            A[r, k] = M[g, k]
        for i in loaded:
            c = force_columns[i]
            for a in range(3):
                A[r, c + a] = -contact_jacobian[3 * i + a, g]
        lower[r] = -bound[r] - h[g]
        upper[r] = bound[r] - h[g]


@numba.njit(cache=True)
def stance_contact_rows(contact_jacobian, contact_drift, contact_desired, loaded, A, lower,
                        upper):
    """``J_c qdd = desired - drift`` for each loaded contact (three world rows each)."""
    nv = contact_jacobian.shape[1]
    for k in range(loaded.size):
        i = loaded[k]
        for a in range(3):
            row, src = 3 * k + a, 3 * i + a
            for j in range(nv):
                A[row, j] = contact_jacobian[src, j]
            rhs = contact_desired[src] - contact_drift[src]
            lower[row] = rhs
            upper[row] = rhs


@numba.njit(cache=True)
def normal_force_bounds(loaded, force_columns, min_force, max_force, lb, ub):
    """Normal force of each loaded contact within ``[min(f_min, f_max), f_max]``."""
    for i in loaded:
        c = force_columns[i] + 2
        ub[c] = max_force[i]
        lb[c] = min(min_force, max_force[i])


@numba.njit(cache=True)
def joint_acceleration_bounds(q, v, q_low, q_high, v_max, horizon, lb, ub):
    """Joint position and velocity limits as acceleration bounds over ``horizon`` [s]."""
    nj = q_low.size
    nq, nv = q.size, v.size
    for k in range(nj):
        qj, vj = q[nq - nj + k], v[nv - nj + k]
        hi = min(2.0 * (q_high[k] - qj - vj * horizon) / (horizon * horizon),
                 (v_max[k] - vj) / horizon)
        lo = max(2.0 * (q_low[k] - qj - vj * horizon) / (horizon * horizon),
                 (-v_max[k] - vj) / horizon)
        lb[nv - nj + k] = min(lo, hi)
        ub[nv - nj + k] = hi


@numba.njit(cache=True)
def support_barrier_rows(com_jacobian, com_position, com_velocity, com_drift, normals, offsets,
                         n_edges, omega, slack_column, A, lower, upper):
    """Centre of mass inside the support polygon: a soft, critically damped barrier.

    ``n_edges`` is a one-element array (so that a cached call sees its changes). Edge ``e``
    of the half-planes ``n_e . p >= o_e`` keeps ``d = n_e . c_xy - o_e`` obeying
    ``d'' + 2 omega d' + omega^2 d >= -s``, relaxed by the slack ``s >= 0``; rows past
    ``n_edges`` are free.
    """
    nv = com_jacobian.shape[1]
    for e in range(A.shape[0]):
        if e < n_edges[0]:
            nx, ny = normals[e, 0], normals[e, 1]
            for k in range(nv):
                A[e, k] = nx * com_jacobian[0, k] + ny * com_jacobian[1, k]
            A[e, slack_column] = 1.0
            distance = nx * com_position[0] + ny * com_position[1] - offsets[e]
            lower[e] = (-(nx * (com_drift[0] + 2.0 * omega * com_velocity[0])
                          + ny * (com_drift[1] + 2.0 * omega * com_velocity[1]))
                        - omega * omega * distance)
            upper[e] = INF
        else:
            for k in range(A.shape[1]):
                A[e, k] = 0.0
            lower[e] = -INF
            upper[e] = INF
