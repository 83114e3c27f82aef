"""The dense QP one control tick solves, and the result a backend returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Bounds at or beyond this magnitude mean "no bound" (DAQP's and OSQP's infinity).
INFINITY = 1e30


class QpProblem:
    """``min 1/2 x^T H x + f^T x`` s.t. ``lower <= A x <= upper`` and ``lb <= x <= ub``.

    Rows flagged in ``is_equality`` have ``lower == upper``. Every array is allocated once
    and updated in place by the controller; backends may keep references to them. The
    bounds are views into two contiguous arrays, ``bupper = [ub; upper]`` and
    ``blower = [lb; lower]`` (DAQP's layout), so no backend has to concatenate them.
    """

    def __init__(self, n: int, m: int):
        """An empty problem with ``n`` variables and ``m`` general rows, all unbounded."""
        self.H = np.zeros((n, n))
        self.f = np.zeros(n)
        self.A = np.zeros((m, n))
        self.bupper = np.full(n + m, INFINITY)
        self.blower = np.full(n + m, -INFINITY)
        self.ub, self.upper = self.bupper[:n], self.bupper[n:]
        self.lb, self.lower = self.blower[:n], self.blower[n:]
        self.is_equality = np.zeros(m, dtype=bool)
        #: Name of the constraint group of each row of ``A`` (for failure diagnosis).
        self.row_groups: list[str] = [""] * m
        #: Incremented whenever ``is_equality`` changes, so backends can cache what
        #: depends on it.
        self.structure_version = 0

    @classmethod
    def zeros(cls, n: int, m: int) -> QpProblem:
        """Same as ``QpProblem(n, m)``."""
        return cls(n, m)

    @property
    def n(self) -> int:
        """Number of variables."""
        return self.H.shape[0]

    @property
    def m(self) -> int:
        """Number of general constraint rows."""
        return self.A.shape[0]

    def violations(self, x: np.ndarray) -> tuple[float, float]:
        """Largest equality and inequality violation of ``x`` (0 when satisfied)."""
        ax = self.A @ x
        rows = np.maximum(np.maximum(self.lower - ax, 0.0), np.maximum(ax - self.upper, 0.0))
        eq = float(rows[self.is_equality].max(initial=0.0))
        ineq = float(max(rows[~self.is_equality].max(initial=0.0),
                         np.maximum(self.lb - x, 0.0).max(initial=0.0),
                         np.maximum(x - self.ub, 0.0).max(initial=0.0)))
        return eq, ineq

    def copy(self) -> QpProblem:
        """A deep copy (for diagnosis off the hot path)."""
        other = QpProblem(self.n, self.m)
        for name in ("H", "f", "A", "bupper", "blower", "is_equality"):
            getattr(other, name)[...] = getattr(self, name)
        other.row_groups = list(self.row_groups)
        other.structure_version = self.structure_version
        return other


@dataclass
class QpResult:
    """What a backend returns: never ``None``, even on failure."""

    found: bool
    x: np.ndarray
    solve_time_s: float
    status: str = "optimal"
    #: Why the solve failed (empty when ``found``).
    reason: str = ""
    iterations: int = 0
