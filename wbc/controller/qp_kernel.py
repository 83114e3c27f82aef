"""Compiled stages of the QP builder: the contact-consistent reduction of the full QP.

Each function is one stage over arrays allocated once per variable layout; none allocates.
The reduction eliminates the floating-base equations of motion and the stance contacts:
with each stance leg's 3x3 contact Jacobian ``L_i`` invertible, the stance joints'
accelerations follow from the base's, ``qdd_i = L_i^-1 (rhs_i - B_i qdd_b)``, and the base's
from the free variables through the six floating-base rows, ``K qdd_b = r0 + E z``. Every
decision variable is then affine in ``z = [swing joints' qdd, contact forces, slacks]``:
``x = T z + t0``, so the QP keeps about 13 variables and no equality rows.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from wbc.controller.cost_kernels import (
    accumulate_tasks,
    add_diagonal_cost,
    add_row_least_squares,
    mirror_upper,
)

INF = 1e30
#: Below this |determinant| (or pivot) the reduction declines and the full QP is solved.
SINGULAR = 1e-9


# The kernels' arguments, grouped by where they come from; each group is gathered once per
# tick plan (one variable layout) and its arrays are updated in place.


class Dynamics(NamedTuple):
    """The robot's mass matrix (nv, nv) and nonlinear effects (nv,) at the last state."""

    M: np.ndarray
    h: np.ndarray


class ContactRows(NamedTuple):
    """The contacts and what the reduction needs to know about them."""

    #: Contact Jacobians (3 c, nv), drifts and desired accelerations (3 c,) of all contacts.
    jacobian: np.ndarray
    drift: np.ndarray
    desired: np.ndarray
    #: The contacts with force variables (k,).
    loaded: np.ndarray
    #: The three acceleration columns of the joints that move each contact (c, 3).
    leg_columns: np.ndarray
    #: The acceleration columns that stay variables of ``z``, in ``z`` order.
    free_columns: np.ndarray
    #: The first force column of ``x``.
    force_start: int


class FullRows(NamedTuple):
    """The full QP's constraints and how they map to the reduced QP's."""

    A: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    #: The full QP's rows the reduced QP keeps (not eliminated).
    kept_rows: np.ndarray
    #: The variable of ``z`` of each column of ``x`` (-1: none).
    z_of_x: np.ndarray
    #: Columns of ``x`` whose bounds become rows of the reduced QP.
    bounded: np.ndarray


class Costs(NamedTuple):
    """The regularisation and the torque-rate term."""

    weights: np.ndarray
    rate_weights: np.ndarray
    x_prev: np.ndarray
    tau_prev: np.ndarray
    torque_rate: float
    #: The first torque row among the reduced rows.
    tau_first: int


class ReducedRows(NamedTuple):
    """What the reduction writes: the map, the reduced QP's arrays, the torque offsets."""

    T: np.ndarray
    t0: np.ndarray
    H: np.ndarray
    f: np.ndarray
    A: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    offset: np.ndarray
    rhs: np.ndarray
    tau_offset: np.ndarray


class Work(NamedTuple):
    """Scratch: the legs' 3x3 blocks and inverses (k, 3, 3), the 6x6 base system, a row."""

    L: np.ndarray
    Linv: np.ndarray
    K: np.ndarray
    X: np.ndarray
    g: np.ndarray


@numba.njit(cache=True)
def reduce_rows(A, lower, upper, rows, T, t0, A_r, lower_r, upper_r, offset):
    """Rows ``rows`` of ``lower <= A x <= upper`` in terms of ``z``: ``A T z + A t0``.

    Writes ``A_r = A T``, the bounds less ``A t0`` (infinite bounds stay infinite) and the
    offsets ``A t0`` (the torque rows' offsets give the torques).
    """
    n, nz = T.shape
    for idx in range(rows.size):
        r = rows[idx]
        A_r[idx, :] = 0.0
        off = 0.0
        for k in range(n):
            a = A[r, k]
            if a != 0.0:
                off += a * t0[k]
                for j in range(nz):
                    A_r[idx, j] += a * T[k, j]
        offset[idx] = off
        lower_r[idx] = lower[r] - off if lower[r] > -INF else -INF
        upper_r[idx] = upper[r] - off if upper[r] < INF else INF


@numba.njit(cache=True)
def reduce_bounds(lb, ub, z_of_x, bounded, T, t0, lb_z, ub_z, A_r, lower_r, upper_r):
    """Bounds on ``x``: simple bounds on ``z`` where ``x_k`` is a variable of ``z``, rows
    ``T_k z`` for the columns ``bounded`` (the stance joints' accelerations)."""
    for k in range(z_of_x.size):
        j = z_of_x[k]
        if j >= 0:
            lb_z[j] = lb[k]
            ub_z[j] = ub[k]
    for idx in range(bounded.size):
        k = bounded[idx]
        A_r[idx, :] = T[k, :]
        lower_r[idx] = lb[k] - t0[k] if lb[k] > -INF else -INF
        upper_r[idx] = ub[k] - t0[k] if ub[k] < INF else INF


@numba.njit(cache=True)
def _inverse3(L, out):
    """``out = L^-1`` for a 3x3 matrix; returns its determinant (0: left unwritten)."""
    det = (L[0, 0] * (L[1, 1] * L[2, 2] - L[1, 2] * L[2, 1])
           - L[0, 1] * (L[1, 0] * L[2, 2] - L[1, 2] * L[2, 0])
           + L[0, 2] * (L[1, 0] * L[2, 1] - L[1, 1] * L[2, 0]))
    if abs(det) < SINGULAR:
        return 0.0
    inv = 1.0 / det
    out[0, 0] = (L[1, 1] * L[2, 2] - L[1, 2] * L[2, 1]) * inv
    out[0, 1] = (L[0, 2] * L[2, 1] - L[0, 1] * L[2, 2]) * inv
    out[0, 2] = (L[0, 1] * L[1, 2] - L[0, 2] * L[1, 1]) * inv
    out[1, 0] = (L[1, 2] * L[2, 0] - L[1, 0] * L[2, 2]) * inv
    out[1, 1] = (L[0, 0] * L[2, 2] - L[0, 2] * L[2, 0]) * inv
    out[1, 2] = (L[0, 2] * L[1, 0] - L[0, 0] * L[1, 2]) * inv
    out[2, 0] = (L[1, 0] * L[2, 1] - L[1, 1] * L[2, 0]) * inv
    out[2, 1] = (L[0, 1] * L[2, 0] - L[0, 0] * L[2, 1]) * inv
    out[2, 2] = (L[0, 0] * L[1, 1] - L[0, 1] * L[1, 0]) * inv
    return det


@numba.njit(cache=True)
def contact_consistent_map(M, h, Jc, rhs, loaded, leg_columns, free_columns, force_start,
                           T, t0, L, Linv, K, X):
    """Fill ``x = T z + t0`` satisfying the floating-base dynamics and the stance contacts.

    Args:
        M (nv, nv), h (nv,): mass matrix and nonlinear effects.
        Jc (3 c, nv), rhs (3 c,): contact Jacobians of all c contacts and ``desired - drift``.
        loaded (k,): the contacts with force variables (stance); their rows of ``Jc`` touch
            the base and their own leg's joints ``leg_columns[i]`` (3,) only.
        free_columns: the acceleration columns that are variables of ``z`` (the other legs'
            joints), in ``z`` order, followed in ``z`` by the forces and slacks, which are
            the columns ``force_start..`` of ``x``.
        T (n, nz), t0 (n,): written.
        L, Linv (k, 3, 3), K (6, 6), X (6, nz + 1): scratch.

    Returns:
        False when a leg's contact Jacobian or the reduced base inertia ``K`` is singular
        (``T`` is then unusable: solve the full QP).
    """
    n, nz = T.shape
    nfree = free_columns.size
    T[:, :] = 0.0
    t0[:] = 0.0
    for j in range(nfree):
        T[free_columns[j], j] = 1.0
    for j in range(n - force_start):
        T[force_start + j, nfree + j] = 1.0
    # K = M_bb - sum_i M_b,leg_i L_i^-1 B_i and the right-hand side [E | r0].
    for a in range(6):
        for b in range(6):
            K[a, b] = M[a, b]
        for j in range(nz + 1):
            X[a, j] = 0.0
        X[a, nz] = -h[a]
        for j in range(nfree):
            X[a, j] = -M[a, free_columns[j]]
    for idx in range(loaded.size):
        i = loaded[idx]
        cols = leg_columns[i]
        for a in range(3):
            for b in range(3):
                L[idx, a, b] = Jc[3 * i + a, cols[b]]
        if _inverse3(L[idx], Linv[idx]) == 0.0:
            return False
        for a in range(6):
            # m = M_b,leg_i[a] L_i^-1 (a row of 3)
            m0 = m1 = m2 = 0.0
            for b in range(3):
                mab = M[a, cols[b]]
                m0 += mab * Linv[idx, b, 0]
                m1 += mab * Linv[idx, b, 1]
                m2 += mab * Linv[idx, b, 2]
            for b in range(6):
                K[a, b] -= (m0 * Jc[3 * i, b] + m1 * Jc[3 * i + 1, b] + m2 * Jc[3 * i + 2, b])
            X[a, nz] -= m0 * rhs[3 * i] + m1 * rhs[3 * i + 1] + m2 * rhs[3 * i + 2]
            for c in range(3):  # the base wrench of this contact's force: B_i^T f_i
                X[a, nfree + 3 * idx + c] = Jc[3 * i + c, a]
    # Solve K Y = X by Gaussian elimination with partial pivoting (6x6, nz + 1 columns).
    for col in range(6):
        pivot, best = col, abs(K[col, col])
        for r in range(col + 1, 6):
            if abs(K[r, col]) > best:
                pivot, best = r, abs(K[r, col])
        if best < SINGULAR:
            return False
        if pivot != col:
            for b in range(6):
                K[col, b], K[pivot, b] = K[pivot, b], K[col, b]
            for j in range(nz + 1):
                X[col, j], X[pivot, j] = X[pivot, j], X[col, j]
        for r in range(col + 1, 6):
            factor = K[r, col] / K[col, col]
            if factor != 0.0:
                for b in range(col, 6):
                    K[r, b] -= factor * K[col, b]
                for j in range(nz + 1):
                    X[r, j] -= factor * X[col, j]
    for col in range(5, -1, -1):
        for j in range(nz + 1):
            s = X[col, j]
            for b in range(col + 1, 6):
                s -= K[col, b] * X[b, j]
            X[col, j] = s / K[col, col]
    for a in range(6):
        for j in range(nz):
            T[a, j] = X[a, j]
        t0[a] = X[a, nz]
    # Stance joints: qdd_i = L_i^-1 (rhs_i - B_i qdd_b).
    for idx in range(loaded.size):
        i = loaded[idx]
        cols = leg_columns[i]
        for a in range(3):
            # u = rhs_i - B_i t0_b, and the rows -B_i T_b
            u0 = rhs[3 * i + a]
            for b in range(6):
                u0 -= Jc[3 * i + a, b] * t0[b]
            X[a, nz] = u0
            for j in range(nz):
                s = 0.0
                for b in range(6):
                    s -= Jc[3 * i + a, b] * T[b, j]
                X[a, j] = s
        for a in range(3):
            c = cols[a]
            t0[c] = (Linv[idx, a, 0] * X[0, nz] + Linv[idx, a, 1] * X[1, nz]
                     + Linv[idx, a, 2] * X[2, nz])
            for j in range(nz):
                T[c, j] = (Linv[idx, a, 0] * X[0, j] + Linv[idx, a, 1] * X[1, j]
                           + Linv[idx, a, 2] * X[2, j])
    return True


@numba.njit(cache=True)
def expand(T, t0, z, x):
    """``x = T z + t0``."""
    n, nz = T.shape
    for k in range(n):
        s = t0[k]
        for j in range(nz):
            s += T[k, j] * z[j]
        x[k] = s


@numba.njit(cache=True)
def reduced_problem(dynamics, contacts, full, tasks, costs, out, work):
    """The whole reduced QP of one tick in one call: the map ``x = T z + t0``, the kept rows
    and the bounds in ``z``, the task costs, the regularisation and the torque-rate term.

    Args:
        dynamics, contacts, full, tasks, costs, out, work: :class:`Dynamics`,
            :class:`ContactRows`, :class:`FullRows`, :class:`TaskRows`, :class:`Costs`,
            :class:`ReducedRows` (written) and :class:`Work` (scratch).

    The torques are ``out.A[tau rows] z + out.tau_offset`` (``costs.tau_first`` is their
    first row among the reduced rows). Returns False when the map is singular (nothing
    else is written): solve the full QP instead.
    """
    h, rhs = dynamics.h, out.rhs
    for r in range(rhs.size):
        rhs[r] = contacts.desired[r] - contacts.drift[r]
    if not contact_consistent_map(dynamics.M, h, contacts.jacobian, rhs, contacts.loaded,
                                  contacts.leg_columns, contacts.free_columns,
                                  contacts.force_start, out.T, out.t0, work.L, work.Linv,
                                  work.K, work.X):
        return False
    T, t0, H, f, A_r, offset = out.T, out.t0, out.H, out.f, out.A, out.offset
    kept = full.kept_rows.size
    reduce_rows(full.A, full.lower, full.upper, full.kept_rows, T, t0, A_r[:kept],
                out.lower[:kept], out.upper[:kept], offset[:kept])
    reduce_bounds(full.lb, full.ub, full.z_of_x, full.bounded, T, t0, out.lb, out.ub,
                  A_r[kept:], out.lower[kept:], out.upper[kept:])
    H[:, :] = 0.0
    f[:] = 0.0
    accumulate_tasks(tasks, T, t0, H, f, work.g)
    add_diagonal_cost(costs.weights, costs.rate_weights, costs.x_prev, T, t0, H, f)
    tau_first, tau_offset = costs.tau_first, out.tau_offset
    nj = tau_offset.size
    nv = h.size
    for k in range(nj):
        tau_offset[k] = offset[tau_first + k] + h[nv - nj + k]
    if costs.torque_rate > 0.0:
        add_row_least_squares(A_r[tau_first:tau_first + nj], tau_offset, costs.tau_prev,
                              costs.torque_rate, H, f)
    mirror_upper(H)
    return True


#: Any float64 vector, read-only or not (a backend's solution: some return read-only arrays).
_ANY_VECTOR = numba.types.Array(numba.types.float64, 1, "A", readonly=True)
_C_VECTOR, _C_MATRIX = numba.types.float64[::1], numba.types.float64[:, ::1]


# An explicit signature: compiled (or read from numba's cache) at import rather than at the
# first tick, which it would stall for milliseconds. The builder's arrays are C-contiguous;
# the solution ``z`` comes from any backend.
@numba.njit(numba.types.void(_C_MATRIX, _C_VECTOR, _ANY_VECTOR, _C_VECTOR, _C_VECTOR, _C_MATRIX,
                             numba.types.int64, _C_VECTOR, _C_VECTOR, numba.types.int64[::1],
                             numba.types.int64, _C_MATRIX), cache=True)
def finish(T, t0, z, x, x_prev, A_r, tau_first, tau_offset, tau, loaded, force_start, forces):
    """From the reduced solution ``z``: ``x = T z + t0`` (also kept as ``x_prev``), the
    torques ``A_r[tau rows] z + tau_offset`` and each contact's force (zero without force
    variables)."""
    expand(T, t0, z, x)
    x_prev[:] = x
    nz = z.size
    for k in range(tau.size):
        s = tau_offset[k]
        for j in range(nz):
            s += A_r[tau_first + k, j] * z[j]
        tau[k] = s
    forces[:, :] = 0.0
    for idx in range(loaded.size):
        for a in range(3):
            forces[loaded[idx], a] = x[force_start + 3 * idx + a]


@numba.njit(cache=True)
def accept(T, t0, z, x, x_prev, A_r, tau_first, tau_offset, tau, loaded, force_start, forces,
           tau_prev):
    """:func:`finish` for a tick solved in compiled code, which also keeps the torques for
    the torque-rate cost (``tau_prev``)."""
    finish(T, t0, z, x, x_prev, A_r, tau_first, tau_offset, tau, loaded, force_start, forces)
    tau_prev[:] = tau
