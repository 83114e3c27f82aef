"""A QP backend that fails on demand, to test what the controller does after a failed solve."""

from __future__ import annotations

import numpy as np

from wbc.backends.backend import QpBackend
from wbc.backends.qp_problem import QpProblem, QpResult


def failing(backend: type[QpBackend], name: str, reason: str = "injected failure"
            ) -> type[QpBackend]:
    """``backend`` reporting a failure (``reason``) for its next ``fail_ticks`` solves."""

    class Failing(backend):  # type: ignore[valid-type, misc]
        def __init__(self) -> None:
            super().__init__()
            self.fail_ticks = 0

        def solve(self, problem: QpProblem) -> QpResult:
            if self.fail_ticks > 0:
                self.fail_ticks -= 1
                return QpResult(found=False, x=np.full(problem.n, np.nan), solve_time_s=0.0,
                                status="injected", reason=reason)
            return super().solve(problem)

    Failing.name = name
    Failing.__name__ = Failing.__qualname__ = f"Failing{backend.__name__}"
    return Failing
