"""QP solver backends behind one small interface, picked by name."""

from wbc.backends.backend import (
    QpBackend,
    available_backends,
    make_backend,
    missing_backends,
    register_backend,
    unregister_backend,
)
from wbc.backends.qp_problem import INFINITY, QpProblem, QpResult

__all__ = [
    "INFINITY", "QpBackend", "QpProblem", "QpResult", "available_backends", "make_backend",
    "missing_backends", "register_backend", "unregister_backend",
]
