"""The small interface every QP backend implements, and the registry that names them."""

from __future__ import annotations

import abc
from collections.abc import Callable
from typing import Any

import numpy as np

from wbc.backends.qp_problem import QpProblem, QpResult
from wbc.core.errors import UnknownNameError


class QpBackend(abc.ABC):
    """Solves :class:`QpProblem` instances of fixed dimensions, tick after tick.

    ``setup`` is called once (and again only if the dimensions change); ``solve`` reads the
    problem's arrays, which the controller has updated in place, and returns a
    :class:`QpResult`. A backend never raises on a failed solve: it returns ``found=False``
    with a reason.
    """

    #: Registry name.
    name: str = ""
    #: The solver's name in messages (``"DAQP"``); the registry name when empty.
    solver_name: str = ""

    @abc.abstractmethod
    def setup(self, problem: QpProblem) -> None:
        """Allocate the solver workspace for problems shaped like ``problem``."""

    @abc.abstractmethod
    def solve(self, problem: QpProblem) -> QpResult:
        """Solve the current ``problem``."""

    def compiled_solve(self, problem: QpProblem) -> tuple[Any, tuple, np.ndarray] | None:
        """A compiled kernel, its arguments, and the array it writes the solution to, that
        solve ``problem`` as :meth:`solve` does (the kernel returns whether it found a
        solution), for a caller that runs it inside its own compiled call
        (:class:`wbc.core.compiled_program.CompiledProgram`); ``None`` (the default): call
        :meth:`solve`. It stays valid while the problem's arrays and structure do."""
        return None

    def prepare(self, problem: QpProblem) -> None:  # noqa: B027 - optional hook, no-op default
        """Build, ahead of its first solve, what solving ``problem`` needs, without changing
        what the next solve of another problem uses (a controller prepares the layouts it
        may switch to). Nothing by default."""


_REGISTRY: dict[str, Callable[[], QpBackend]] = {}
_MISSING: dict[str, str] = {}


def register_backend(name: str, factory: Callable[[], QpBackend]) -> None:
    """Make a backend available under ``name``."""
    _REGISTRY[name] = factory


def unregister_backend(name: str) -> None:
    """Remove a backend registered with :func:`register_backend` (e.g. a test's)."""
    _load_all()
    if name not in _REGISTRY:
        raise UnknownNameError(
            f"unknown backend {name!r}; installed backends: {', '.join(sorted(_REGISTRY))}")
    del _REGISTRY[name]


def register_missing(name: str, reason: str) -> None:
    """Record why a backend is not available (shown when someone asks for it)."""
    _MISSING[name] = reason


def available_backends() -> list[str]:
    """Names of the backends installed on this machine."""
    _load_all()
    return sorted(_REGISTRY)


def missing_backends() -> dict[str, str]:
    """Backends this library knows of but cannot use here, with the reason."""
    _load_all()
    return dict(_MISSING)


def make_backend(name: str) -> QpBackend:
    """A new backend instance by name; an unknown name lists the installed ones."""
    _load_all()
    if name not in _REGISTRY:
        hint = f" ({_MISSING[name]})" if name in _MISSING else ""
        raise UnknownNameError(
            f"unknown backend {name!r}{hint}; installed backends: {', '.join(sorted(_REGISTRY))}"
        )
    return _REGISTRY[name]()


def _load_all() -> None:
    # Imported here so that a missing solver only removes its own backend.
    from wbc.backends import daqp_backend, osqp_backend, qpsolvers_backend  # noqa: F401
