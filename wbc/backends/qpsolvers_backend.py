"""Any solver qpsolvers has installed, through its one-shot ``solve_problem`` call."""

from __future__ import annotations

import time
from collections.abc import Collection
from functools import partial

import numpy as np

from wbc.backends.backend import QpBackend, register_backend, register_missing
from wbc.backends.qp_problem import INFINITY, QpProblem, QpResult

try:
    import qpsolvers
except ImportError as err:  # pragma: no cover - depends on the machine
    qpsolvers = None
    register_missing("qpsolvers", f"package 'qpsolvers' not importable: {err}")

#: Solvers whose one-shot call this library registers (when qpsolvers sees them).
SOLVERS = ("clarabel", "cvxopt", "daqp", "ecos", "highs", "osqp", "piqp", "proxqp", "qpalm",
           "quadprog", "scs")
#: Solvers this package installs only through an optional extra: (extra, licence). quadprog is
#: GPL-2.0-or-later, so it stays out of the BSD-3 package's required dependencies.
EXTRAS = {"quadprog": ("solvers", "GPL-2.0-or-later")}
#: Tight tolerances where qpsolvers passes them on, so solutions are comparable.
_SETTINGS = {
    "osqp": {"eps_abs": 1e-7, "eps_rel": 1e-7, "polishing": True, "max_iter": 20000},
    "proxqp": {"eps_abs": 1e-9},
    "piqp": {"eps_abs": 1e-9, "eps_rel": 1e-9},
    "clarabel": {"tol_feas": 1e-9, "tol_gap_abs": 1e-9},
}


class QpsolversBackend(QpBackend):
    """A new problem per tick through ``qpsolvers.solve_problem`` (no persistent workspace).

    Converts the two-sided rows to qpsolvers' ``G x <= h``, ``A x = b``: the reference a
    newcomer would write first, and the baseline the persistent backends are timed against.
    """

    def __init__(self, solver: str):
        self.solver = solver
        self.name = f"qpsolvers:{solver}"
        self.solver_name = f"{solver} (qpsolvers)"

    def setup(self, problem: QpProblem) -> None:
        """Nothing to keep between ticks."""

    def solve(self, problem: QpProblem) -> QpResult:
        start = time.perf_counter()
        lb = np.where(problem.lb <= -INFINITY, -np.inf, problem.lb)
        ub = np.where(problem.ub >= INFINITY, np.inf, problem.ub)
        # A variable pinned by equal bounds (a released foot's force) is an equality row:
        # some solvers (quadprog) read lb == ub as two opposite inequalities and fail, and
        # rows on pinned variables alone (its friction rows, 0 <= 0) are dependent: dropped.
        pinned = np.flatnonzero(lb == ub)
        free = np.ones(problem.n, dtype=bool)
        free[pinned] = False
        eq = problem.is_equality
        ineq = ~eq & np.any(problem.A[:, free] != 0.0, axis=1)
        has_up = ineq & (problem.upper < INFINITY)
        has_low = ineq & (problem.lower > -INFINITY)
        G = np.vstack([problem.A[has_up], -problem.A[has_low]])
        h = np.concatenate([problem.upper[has_up], -problem.lower[has_low]])
        A_eq = np.vstack([problem.A[eq], np.eye(problem.n)[pinned]])
        b_eq = np.concatenate([problem.upper[eq], lb[pinned]])
        lb[pinned], ub[pinned] = -np.inf, np.inf
        qp = qpsolvers.Problem(problem.H, problem.f, G, h, A_eq, b_eq, lb, ub)
        try:
            solution = qpsolvers.solve_problem(qp, solver=self.solver,
                                               **_SETTINGS.get(self.solver, {}))
            x, found = solution.x, bool(solution.found)
            reason = "" if found else f"{self.solver}: no solution found"
        except Exception as err:  # noqa: BLE001 - eleven third-party solvers, any error type
            # qpsolvers wraps only some solver errors in its QPError; others come through in the
            # solver's own types (ValueError, ArithmeticError, RuntimeError, extension errors),
            # and a failed solve must reach the controller as found=False, not as an exception.
            x, found, reason = None, False, f"{self.solver}: {type(err).__name__}: {err}"
        elapsed = time.perf_counter() - start
        if x is None or not np.all(np.isfinite(x)):
            x, found = np.full(problem.n, np.nan), False
            reason = reason or f"{self.solver}: non-finite solution"
        return QpResult(found=found, x=np.asarray(x, dtype=float), solve_time_s=elapsed,
                        status="optimal" if found else "failed", reason=reason)


def missing_reason(solver: str) -> str:
    """Why ``qpsolvers:<solver>`` is not available: the extra that installs it, if one does."""
    if solver in EXTRAS:
        extra, licence = EXTRAS[solver]
        return (f"{solver} is not installed ({licence}, an optional extra): "
                f"pip install 'go2-wbc[{extra}]'")
    return f"qpsolvers does not see solver {solver!r} on this machine"


def register_solvers(available: Collection[str]) -> None:
    """Register ``qpsolvers:<name>`` for each of :data:`SOLVERS` in ``available`` (qpsolvers'
    ``available_solvers``), and the reason for each other one."""
    for solver in SOLVERS:
        if solver in available:
            register_backend(f"qpsolvers:{solver}", partial(QpsolversBackend, solver))
        else:
            register_missing(f"qpsolvers:{solver}", missing_reason(solver))


if qpsolvers is not None:
    register_solvers(qpsolvers.available_solvers)
