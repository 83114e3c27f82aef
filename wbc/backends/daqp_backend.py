"""DAQP, a dense dual active-set solver: the default backend."""

from __future__ import annotations

import ctypes
import importlib.metadata
import logging
import math
import time
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

from wbc.backends.backend import QpBackend, register_backend, register_missing
from wbc.backends.qp_problem import QpProblem, QpResult

try:
    import daqp
except ImportError as err:  # pragma: no cover - depends on the machine
    daqp = None
    register_missing("daqp", f"package 'daqp' not importable: {err}")

logger = logging.getLogger(__name__)

_EQUALITY = 5  # DAQP constraint sense of an equality row
_ACTIVE = 1    # DAQP sense flag: start with this constraint in the active set
_LOWER = 2     # DAQP sense flag: ... at its lower bound (negative multiplier)
_EXIT_FLAGS = {
    1: "optimal", 2: "soft optimal", -1: "infeasible", -2: "cycling", -3: "unbounded",
    -4: "iteration limit", -5: "nonconvex", -6: "overdetermined initial active set",
}


#: The DAQP releases whose C structures :class:`_DirectCall` lays out (DAQP's ``types.h``
#: and ``api.h``); any other release is called through its Python wrapper.
_DIRECT_RELEASES = ("0.11.",)
_c_double_p = ctypes.POINTER(ctypes.c_double)
_c_int_p = ctypes.POINTER(ctypes.c_int)
# Room after each structure's known fields: a field a release adds cannot write past it.
_SPARE = 256


class _CProblem(ctypes.Structure):
    _fields_ = [("n", ctypes.c_int), ("m", ctypes.c_int), ("ms", ctypes.c_int),
                ("H", _c_double_p), ("f", _c_double_p), ("A", _c_double_p),
                ("bupper", _c_double_p), ("blower", _c_double_p), ("sense", _c_int_p),
                ("bin_ids", _c_int_p), ("nb", ctypes.c_int), ("spare", ctypes.c_char * _SPARE)]


class _CResult(ctypes.Structure):
    _fields_ = [("x", _c_double_p), ("lam", _c_double_p), ("fval", ctypes.c_double),
                ("soft_slack", ctypes.c_double), ("exitflag", ctypes.c_int),
                ("iter", ctypes.c_int), ("nodes", ctypes.c_int),
                ("solve_time", ctypes.c_double), ("setup_time", ctypes.c_double),
                ("spare", ctypes.c_char * _SPARE)]


class _CSettings(ctypes.Structure):
    _fields_ = [("primal_tol", ctypes.c_double), ("dual_tol", ctypes.c_double),
                ("zero_tol", ctypes.c_double), ("pivot_tol", ctypes.c_double),
                ("progress_tol", ctypes.c_double), ("cycle_tol", ctypes.c_int),
                ("iter_limit", ctypes.c_int), ("spare", ctypes.c_char * _SPARE)]


class _DirectCall:
    """``daqp_quadprog`` called on one problem's arrays through ctypes, its structures built
    once: about 2.5 us a solve here, where ``daqp.solve`` (which builds them, and the
    output arrays and an info dict, on every call) takes about 6.

    The problem's arrays are held, and checked by identity on every call: an array replaced
    on the problem means a new call is built (:meth:`fits`).
    """

    _function = None

    def __init__(self, problem: QpProblem, sense: np.ndarray, *, primal_tol: float,
                 iter_limit: int):
        self.arrays = (problem.H, problem.f, problem.A, problem.bupper, problem.blower, sense)
        for array in self.arrays:
            if not array.flags.c_contiguous:
                raise ValueError("DAQP's arrays must be C-contiguous")
        self.x = np.zeros(problem.n)
        self.lam = np.zeros(problem.n + problem.m)
        qp = self.problem = _CProblem()
        qp.n, qp.m, qp.ms, qp.nb = problem.n, problem.n + problem.m, problem.n, 0
        qp.H, qp.f, qp.A, qp.bupper, qp.blower = (
            a.ctypes.data_as(_c_double_p) for a in self.arrays[:5])
        qp.sense = sense.ctypes.data_as(_c_int_p)
        self.result = _CResult()
        self.result.x = self.x.ctypes.data_as(_c_double_p)
        self.result.lam = self.lam.ctypes.data_as(_c_double_p)
        self.settings = _CSettings()
        function = self.function()
        _library().daqp_default_settings(ctypes.byref(self.settings))
        self.settings.primal_tol, self.settings.iter_limit = primal_tol, iter_limit
        self._call = (function, ctypes.addressof(self.result), ctypes.addressof(qp),
                      ctypes.addressof(self.settings))

    @staticmethod
    def function():
        """``daqp_quadprog`` from the installed extension (``None`` if it cannot be used)."""
        if _DirectCall._function is None:
            lib = _library()
            lib.daqp_default_settings.argtypes = [ctypes.c_void_p]
            lib.daqp_default_settings.restype = None
            call = lib.daqp_quadprog
            call.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
            call.restype = None
            _DirectCall._function = call
        return _DirectCall._function

    def fits(self, problem: QpProblem, sense: np.ndarray) -> bool:
        """Whether this call still points at the problem's arrays."""
        H, f, A, bupper, blower, held_sense = self.arrays
        return (problem.H is H and problem.f is f and problem.A is A
                and problem.bupper is bupper and problem.blower is blower
                and sense is held_sense)

    def compiled(self) -> tuple[Any, tuple, np.ndarray]:
        """:func:`direct_solve` and its arguments on this call's structures (held by the
        address array, which keeps this call alive)."""
        function = ctypes.cast(self.function(), ctypes.c_void_p).value
        addresses = _Addresses([function, ctypes.addressof(self.result),
                                ctypes.addressof(self.problem), ctypes.addressof(self.settings)])
        addresses.call = self
        flag = ctypes.addressof(self.result) + _CResult.exitflag.offset
        exitflag = np.ctypeslib.as_array((ctypes.c_int * 1).from_address(flag))
        return direct_solve, (addresses, exitflag, self.x), self.x

    def __call__(self) -> tuple[int, int]:
        """Solve into :attr:`x` and :attr:`lam`; DAQP's exit flag and iteration count."""
        function, result, problem, settings = self._call
        function(result, problem, settings)
        return self.result.exitflag, self.result.iter


@intrinsic
def _call_c(typingctx, addresses):  # pragma: no cover - compiled
    """Call ``void f(void *, void *, void *)`` at ``addresses[0]`` with ``addresses[1:4]``."""
    def codegen(context, builder, signature, args):
        array = context.make_array(signature.args[0])(context, builder, args[0])
        pointer = ir.IntType(8).as_pointer()
        values = [builder.load(builder.gep(array.data, [ir.IntType(64)(i)])) for i in range(4)]
        function = builder.inttoptr(values[0], ir.FunctionType(
            ir.VoidType(), [pointer] * 3).as_pointer())
        builder.call(function, [builder.inttoptr(v, pointer) for v in values[1:]])
        return context.get_dummy_value()
    return types.void(addresses), codegen


@numba.njit(cache=True)
def direct_solve(addresses, exitflag, x):  # pragma: no cover - compiled
    """``daqp_quadprog`` at ``addresses[0]`` on the result, problem and settings structures
    at ``addresses[1:4]``; whether it found a finite solution (``exitflag`` views the
    result's exit flag, ``x`` its solution)."""
    _call_c(addresses)
    if exitflag[0] != 1 and exitflag[0] != 2:
        return False
    for i in range(x.size):
        if not math.isfinite(x[i]):
            return False
    return True


class _Addresses(np.ndarray):
    """An int64 array of addresses that holds what they point into (``call``)."""

    call: Any = None

    def __new__(cls, values: list[int]) -> _Addresses:
        return np.asarray(values, dtype=np.int64).view(cls)


def _library() -> ctypes.CDLL:
    return ctypes.CDLL(daqp.__file__)


def _direct_call_works() -> bool:
    """Whether this DAQP release is one whose structures we lay out, and a direct call
    gives the wrapper's solution on a small QP with equality, bounds and inequalities."""
    if daqp is None:
        return False
    try:
        release = importlib.metadata.version("daqp")
    except importlib.metadata.PackageNotFoundError:  # pragma: no cover - odd installs
        return False
    if not release.startswith(_DIRECT_RELEASES):
        logger.info("DAQP %s: called through its Python wrapper (direct calls are laid out "
                    "for %s)", release, ", ".join(_DIRECT_RELEASES))
        return False
    try:
        problem = QpProblem(3, 2)
        problem.H[:] = [[4.0, 1.0, 0.0], [1.0, 3.0, 0.5], [0.0, 0.5, 2.0]]
        problem.f[:] = [1.0, -2.0, 0.5]
        problem.A[:] = [[1.0, 1.0, 1.0], [1.0, -1.0, 0.0]]
        problem.lower[:], problem.upper[:] = [1.0, -np.inf], [1.0, 0.2]
        problem.lb[:], problem.ub[:] = [-1.0, 0.0, -1.0], [1.0, 0.6, 1.0]
        sense = np.zeros(5, dtype=np.int32)
        sense[3] = _EQUALITY
        call = _DirectCall(problem, sense, primal_tol=1e-9, iter_limit=100)
        flag, _ = call()
        x, _, expected_flag, _ = daqp.solve(problem.H, problem.f, problem.A, problem.bupper,
                                            problem.blower, sense.copy(), primal_tol=1e-9,
                                            iter_limit=100)
        return flag == expected_flag == 1 and np.allclose(call.x, x, atol=1e-12, rtol=0.0)
    except (AttributeError, OSError, ValueError) as err:  # pragma: no cover - odd installs
        logger.info("DAQP: called through its Python wrapper (%s)", err)
        return False


#: How many problems' structures a backend keeps (a controller uses about five layouts).
_KEPT_PROBLEMS = 16


@dataclass
class _ProblemState:
    """What one problem's solves reuse: its ``sense`` flags (with the hot start's active
    set), the flags it started from, and the direct call on its arrays."""

    problem: QpProblem
    version: int
    sense: np.ndarray
    base_sense: np.ndarray
    call: _DirectCall | None


class DaqpBackend(QpBackend):
    """DAQP called once per tick on the problem's arrays, in place (no copies).

    Measured on this 31-variable problem: ``daqp.Model.update`` re-runs DAQP's setup (the
    factorisation of ``H`` and the transformed constraints) whenever ``H`` or ``A`` change,
    as they do every tick, and its wrapper made it slower than one ``daqp.solve`` call
    (about 60 us against 45 us). DAQP's setup dominates: it then converges in one or two
    active-set iterations from a cold start, so no warm start is passed.

    On the pinned DAQP release the solve calls DAQP's C function directly, with its
    structures built once per problem (:class:`_DirectCall`, checked against the wrapper
    when first used); on any other release, through ``daqp.solve``.
    """

    name = "daqp"
    solver_name = "DAQP"
    #: Whether direct calls work on this installation (decided on first use).
    _direct_ok: bool | None = None

    def __init__(self, *, primal_tol: float = 1e-9, iter_limit: int = 1000,
                 hot_start: bool = False, direct: bool = True):
        """Args:
            primal_tol: Primal feasibility tolerance (constraint violation it accepts).
            iter_limit: Active-set iteration limit.
            hot_start: Start each solve from the active set of the last solve of the same
                problem (DAQP's "active" sense flag; each QP layout keeps its own), while
                its structure is unchanged.
            direct: Call DAQP's C function directly where this DAQP release allows it
                (``False``: always through ``daqp.solve``).
        """
        self.settings = {"primal_tol": primal_tol, "iter_limit": iter_limit}
        self.hot_start = hot_start
        self.direct = direct
        self._state: _ProblemState | None = None
        #: The state of each problem solved lately, by ``id``: a controller switches between
        #: a few layouts' problems as feet lift and land, and each keeps its structures.
        self._states: dict[int, _ProblemState] = {}

    def setup(self, problem: QpProblem) -> None:
        """Build the problem's structures anew (also after a failure: DAQP's may be spent)."""
        sense = np.zeros(problem.n + problem.m, dtype=np.int32)
        sense[problem.n:][problem.is_equality] = _EQUALITY
        call = None
        if self.direct:
            if DaqpBackend._direct_ok is None:
                DaqpBackend._direct_ok = _direct_call_works()
            if DaqpBackend._direct_ok:
                call = _DirectCall(problem, sense, **self.settings)
        state = _ProblemState(problem, problem.structure_version, sense, sense.copy(), call)
        self._states.pop(id(problem), None)
        while len(self._states) >= _KEPT_PROBLEMS:  # the oldest goes
            del self._states[next(iter(self._states))]
        self._states[id(problem)] = self._state = state

    def prepare(self, problem: QpProblem) -> None:
        if not self._usable(self._states.get(id(problem)), problem):
            current = self._state
            self.setup(problem)
            self._state = current

    def compiled_solve(self, problem: QpProblem) -> tuple[Any, tuple, np.ndarray] | None:
        """DAQP's C function called from compiled code on the problem's direct call (see
        :meth:`QpBackend.compiled_solve`); ``None`` with a hot start, without direct calls,
        or in a subclass that overrides :meth:`solve` (its own solve must be the one called)."""
        if self.hot_start or type(self).solve is not DaqpBackend.solve:
            return None
        self.prepare(problem)
        state = self._states[id(problem)]
        return None if state.call is None else state.call.compiled()

    @property
    def uses_direct_call(self) -> bool:
        """Whether the last solve called DAQP's C function directly (else ``daqp.solve``)."""
        return self._state is not None and self._state.call is not None

    @staticmethod
    def _usable(state: _ProblemState | None, problem: QpProblem) -> bool:
        """Whether ``state`` was built for ``problem`` as it is now (structure and arrays)."""
        return (state is not None and state.problem is problem
                and state.version == problem.structure_version
                and (state.call is None or state.call.fits(problem, state.sense)))

    def solve(self, problem: QpProblem) -> QpResult:
        state = self._state
        if not self._usable(state, problem):
            state = self._states.get(id(problem))
            if self._usable(state, problem):
                self._state = state
            else:  # new, changed, or an array replaced on the problem
                self.setup(problem)
                state = self._state
        call = state.call
        start = time.perf_counter()
        if call is not None:
            exitflag, iterations = call()
            x, lam = call.x.copy(), call.lam
        else:
            settings = self.settings
            x, _, exitflag, info = daqp.solve(problem.H, problem.f, problem.A, problem.bupper,
                                              problem.blower, state.sense,
                                              primal_tol=settings["primal_tol"],
                                              iter_limit=settings["iter_limit"])
            iterations, lam = int(info.get("iterations", 0)), info.get("lam")
        elapsed = time.perf_counter() - start
        # A finite sum means a finite solution (a NaN or an infinity would show in it); over
        # Python floats it is cheaper than any NumPy reduction at this size.
        found = (exitflag == 1 or exitflag == 2) and math.isfinite(sum(x.tolist()))
        if self.hot_start:  # the next solve starts from this active set (a solved one only)
            sense = state.sense
            np.copyto(sense, state.base_sense)
            if found:
                sense[lam != 0.0] |= _ACTIVE
                sense[lam < 0.0] |= _LOWER
        if found:
            return QpResult(found=True, x=x, solve_time_s=elapsed, iterations=iterations)
        status = _EXIT_FLAGS.get(exitflag, f"exit flag {exitflag}")
        return QpResult(found=False, x=np.asarray(x, dtype=float), solve_time_s=elapsed,
                        status=status, reason=f"DAQP: {status}", iterations=iterations)


if daqp is not None:
    register_backend("daqp", DaqpBackend)
    register_backend("daqp-hot", lambda: DaqpBackend(hot_start=True))
