"""Compiled stages of the QP's cost: the stacked tasks' rows and the small quadratic terms.

Each adds to ``1/2 z^T H z + f^T z`` (the upper triangle of ``H``) for decision variables
``x = T z + t0``: the full QP's ``T`` is the identity, the reduced QP's the map of
:mod:`wbc.controller.qp_kernel`. None allocates.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np


class TaskRows(NamedTuple):
    """The registered tasks' rows, stacked (:class:`wbc.controller.task_stack.TaskStack`)."""

    #: Every row's Jacobian entries, row after row (row ``r`` is ``row_offset[r]`` to
    #: ``row_offset[r + 1]``: the widths of its task's variables).
    jacobian: np.ndarray
    row_offset: np.ndarray
    drift: np.ndarray
    desired: np.ndarray
    row_weights: np.ndarray
    #: The task of each row.
    row_task: np.ndarray
    #: kp, kd, weight of each task (tasks, 3).
    gains: np.ndarray
    #: Whether each task is in the QP (tasks,).
    active: np.ndarray
    #: The column of ``x`` of each task's Jacobian column (tasks, widest), -1: none.
    columns: np.ndarray


@numba.njit(cache=True)
def accumulate_tasks(tasks, T, t0, H, f, g):
    """``H += w (J_x T)^T (J_x T)``, ``f += w (J_x T)^T (J_x t0 + drift - desired)`` per task
    row, where ``J_x`` is the row spread over the columns of ``x`` its task spans.

    Args:
        tasks: The stacked task rows (:class:`TaskRows`).
        T (n, nz), t0 (n,): the map from the QP's variables to ``x``.
        H (nz, nz), f (nz,): accumulated (upper triangle of ``H``).
        g (nz,): scratch.
    """
    nz = T.shape[1]
    J, offsets, columns = tasks.jacobian, tasks.row_offset, tasks.columns
    for r in range(tasks.drift.size):
        t = tasks.row_task[r]
        if not tasks.active[t]:
            continue
        w = tasks.gains[t, 2] * tasks.row_weights[r]
        if w == 0.0:
            continue
        g[:] = 0.0
        residual = tasks.drift[r] - tasks.desired[r]
        start = offsets[r]
        for k in range(offsets[r + 1] - start):
            a = J[start + k]
            if a != 0.0:
                c = columns[t, k]
                if c < 0:  # a variable this layout does not have (a lifted foot's force)
                    continue
                residual += a * t0[c]
                for j in range(nz):
                    g[j] += a * T[c, j]
        for i in range(nz):
            wg = w * g[i]
            if wg != 0.0:
                f[i] += wg * residual
                for j in range(i, nz):
                    H[i, j] += wg * g[j]


@numba.njit(cache=True)
def add_diagonal_cost(weights, rate_weights, x_prev, T, t0, H, f):
    """Cost ``1/2 sum_k weights_k x_k^2 - rate_weights_k x_prev_k x_k`` with ``x = T z + t0``.

    ``weights`` holds the regularisation plus the rate weights, so with ``rate_weights``
    this is ``1/2 |x|^2_reg + 1/2 |x - x_prev|^2_rate`` up to a constant.
    """
    nz = T.shape[1]
    for k in range(T.shape[0]):
        d = weights[k]
        c = d * t0[k] - rate_weights[k] * x_prev[k]
        for i in range(nz):
            tki = T[k, i]
            if tki == 0.0:
                continue
            f[i] += tki * c
            if d != 0.0:
                dt = d * tki
                for j in range(i, nz):
                    H[i, j] += dt * T[k, j]


@numba.njit(cache=True)
def add_row_least_squares(A, offset, target, weight, H, f):
    """``H += w A^T A``, ``f += w A^T (offset - target)``: the cost
    ``w/2 |A z + offset - target|^2``."""
    nz = A.shape[1]
    for r in range(A.shape[0]):
        residual = offset[r] - target[r]
        for i in range(nz):
            wa = weight * A[r, i]
            if wa != 0.0:
                f[i] += wa * residual
                for j in range(i, nz):
                    H[i, j] += wa * A[r, j]


@numba.njit(cache=True)
def mirror_upper(H):
    """Copy the upper triangle of ``H`` onto the lower one."""
    n = H.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            H[j, i] = H[i, j]
