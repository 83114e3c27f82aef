"""OSQP with a persistent workspace: set up once, then updated in place every tick."""

from __future__ import annotations

import time

import numpy as np

from wbc.backends.backend import QpBackend, register_backend, register_missing
from wbc.backends.qp_problem import QpProblem, QpResult

try:
    import osqp
    import scipy.sparse as sp
except ImportError as err:  # pragma: no cover - depends on the machine
    osqp = None
    register_missing("osqp", f"package 'osqp' not importable: {err}")


class OsqpBackend(QpBackend):
    """OSQP, the operator-splitting solver, warm-started and updated in place.

    The sparsity pattern is dense (every entry of ``H``'s upper triangle and of ``[I; A]``),
    so any new values fit the workspace set up on the first tick: no new factorisation
    structure, no new setup. Tolerances are tight and the solution is polished: at OSQP's
    default tolerance (1e-3) the friction constraints of this problem are violated by about
    1e-3.

    OSQP 1.1 prints "Polishing not needed - no active set detected at optimal point" to
    standard output on every solve whose active set is empty, ``verbose`` or not (OSQP's
    issue 785); this backend does not hide it, since redirecting the process's output is
    not safe in a threaded program (``benchmarks.qp_timing`` does, around its episodes).
    """

    name = "osqp"
    solver_name = "OSQP"

    def __init__(self, *, eps_abs: float = 1e-7, eps_rel: float = 1e-7, max_iter: int = 20000,
                 polish: bool = True):
        self.settings = {"eps_abs": eps_abs, "eps_rel": eps_rel, "max_iter": max_iter,
                         "polishing": polish, "verbose": False, "warm_starting": True}
        self._solver = None
        self._shape: tuple[int, int] | None = None

    def setup(self, problem: QpProblem) -> None:
        n, m = problem.n, problem.m
        self._upper_tri = np.triu_indices(n)
        dense_p = np.ones((n, n))
        self._P = sp.csc_matrix(np.triu(dense_p))
        # CSC stores column-major: the value order of a dense upper triangle.
        cols = [(i, j) for j in range(n) for i in range(j + 1)]
        self._p_rows = np.array([c[0] for c in cols])
        self._p_cols = np.array([c[1] for c in cols])
        stacked = np.ones((n + m, n))
        self._A = sp.csc_matrix(stacked)
        self._stacked = np.zeros((n + m, n))
        self._stacked[:n] = np.eye(n)
        self._fill(problem)
        self._P.data[:] = problem.H[self._p_rows, self._p_cols]
        self._A.data[:] = self._stacked.T.reshape(-1)
        self._solver = osqp.OSQP()
        self._solver.setup(P=self._P, q=problem.f, A=self._A, l=self._l, u=self._u,
                           **self.settings)
        self._shape = (n, m)

    def _fill(self, problem: QpProblem) -> None:
        self._stacked[problem.n:] = problem.A
        # OSQP reads bounds of magnitude >= 1e30 as infinite, the problem's convention.
        self._l, self._u = problem.blower, problem.bupper

    def solve(self, problem: QpProblem) -> QpResult:
        start = time.perf_counter()
        if self._shape != (problem.n, problem.m):
            self.setup(problem)
        else:
            self._fill(problem)
            self._solver.update(q=problem.f, l=self._l, u=self._u,
                                Px=problem.H[self._p_rows, self._p_cols],
                                Ax=self._stacked.T.reshape(-1))
        result = self._solver.solve(raise_error=False)  # failures are reported, not raised
        elapsed = time.perf_counter() - start
        status = str(result.info.status)
        x = result.x if result.x is not None else np.full(problem.n, np.nan)
        found = status == "solved" and np.all(np.isfinite(x))
        return QpResult(found=bool(found), x=np.asarray(x, dtype=float), solve_time_s=elapsed,
                        status=status, reason="" if found else f"OSQP: {status}",
                        iterations=int(result.info.iter))


if osqp is not None:
    register_backend("osqp", OsqpBackend)
