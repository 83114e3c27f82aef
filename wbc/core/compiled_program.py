"""Several compiled kernels run as one compiled call, their arrays gathered once by address."""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic


class Guard(NamedTuple):
    """A step whose kernel returns whether the program goes on: when it returns False, the
    program stops there and returns False (a program that runs to its end after a guard
    returns True)."""

    kernel: Any
    arguments: tuple


#: A kernel and every one of its arguments, a :class:`Guard`, or a Python callable of no
#: arguments.
Step = tuple[Any, tuple] | Guard | Callable[[], Any]

_POINTERS = {np.dtype(np.float64): types.float64, np.dtype(np.int64): types.int64,
             np.dtype(np.int32): types.int32, np.dtype(np.bool_): types.boolean}


def _pointer_intrinsic(dtype: types.Type) -> Any:
    @intrinsic
    def pointer(typingctx: Any, address: Any) -> Any:  # pragma: no cover - compiled
        pointer_type = types.CPointer(dtype)

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            return builder.inttoptr(args[0], context.get_value_type(pointer_type))
        return pointer_type(types.int64), codegen
    return pointer


#: ``address -> pointer`` of each dtype an array may have in a program, by the name the
#: generated code calls it.
_POINTER_OF = {dtype: (f"_p_{dtype.name}", _pointer_intrinsic(numba_type))
               for dtype, numba_type in _POINTERS.items()}
#: The compiled programs of this process, by their source and the objects they name.
_PROGRAMS: dict[tuple, Any] = {}


class _Writer:
    """Turns the steps' arguments into source: arrays read from the address table, NamedTuples
    rebuilt, scalars as literals, anything else passed through ``extra``."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.names: dict[str, Any] = {}
        self.addresses: list[int] = []
        self.arrays: list[np.ndarray] = []  # held: the table points into them
        self.extra: list[Any] = []
        self._array_names: dict[int, str] = {}

    def name(self, prefix: str, value: Any) -> str:
        for name, held in self.names.items():
            if held is value:
                return name
        name = f"{prefix}{len(self.names)}"
        self.names[name] = value
        return name

    def expression(self, value: Any) -> str:
        if isinstance(value, np.ndarray):
            return self._array(value)
        if isinstance(value, (bool, np.bool_)):
            return repr(bool(value))
        if isinstance(value, (int, np.integer)):
            return repr(int(value))
        if isinstance(value, (float, np.floating)) and np.isfinite(value):
            return repr(float(value))
        if isinstance(value, tuple) and hasattr(value, "_fields"):
            fields = ", ".join(self.expression(v) for v in value)
            return f"{self.name('_nt', type(value))}({fields})"
        if isinstance(value, tuple):
            return "(" + "".join(self.expression(v) + ", " for v in value) + ")"
        self.extra.append(value)
        return f"extra[{len(self.extra) - 1}]"

    def _array(self, array: np.ndarray) -> str:
        name = self._array_names.get(id(array))
        if name is not None:
            return name
        pointer = _POINTER_OF.get(array.dtype)
        if pointer is None or not array.flags.c_contiguous or array.size == 0:
            self.extra.append(array)
            return f"extra[{len(self.extra) - 1}]"
        self.names[pointer[0]] = pointer[1]
        name = f"a{len(self.arrays)}"
        self.lines.append(f"    {name} = carray({pointer[0]}(table[{len(self.addresses)}]), "
                          f"{tuple(array.shape)!r})")
        self.addresses.append(array.ctypes.data)
        self.arrays.append(array)
        self._array_names[id(array)] = name
        return name


class CompiledProgram:
    """Steps run in order as few compiled calls as they allow: each run of consecutive
    compiled kernels becomes one generated ``numba.njit`` function, which reads every array
    of its kernels' arguments from a table of addresses made once (one array to pass a tick,
    where passing the arrays themselves costs numba about 30 ns each to unbox, some 180 a
    tick), with the arrays' shapes and the scalars written in as constants.

    A step is ``(kernel, arguments)``, a ``numba.njit`` dispatcher and all its arguments, or a
    Python callable of no arguments (a task written in NumPy), which runs between the
    compiled calls in its place. Calling the program returns the last step's result.

    The arrays must stay the same objects, alive and updated in place (as for
    :func:`wbc.core.compiled_call.bind_compiled`); arrays that are not C-contiguous, or of
    another dtype, and other arguments are passed as they are. Generated functions are
    compiled once a process for each source (the same layout of another controller reuses
    it) and cached on disk by numba, next to their source in the program cache directory
    (``GO2_WBC_PROGRAM_DIR``, else ``~/.cache/go2-wbc/programs``), named by a hash of the
    source and of the kernels' module files, so an edited kernel makes a new program.
    """

    def __init__(self, steps: Sequence[Step]):
        """Args:
            steps: The kernels and callables, in the order they must run.
        """
        self._parts: list[Callable[[], Any]] = []
        run: list[tuple[Any, tuple]] = []
        for step in steps:
            if isinstance(step, tuple):
                run.append(step)
                continue
            if run:
                self._parts.append(_compile(run))
                run = []
            self._parts.append(step)
        if run:
            self._parts.append(_compile(run))
        #: How many calls a run of the program makes (compiled and Python).
        self.calls = len(self._parts)
        #: Runs every step and returns the last one's result: the one compiled call itself
        #: when the steps make one (no Python frame around it).
        self.run: Callable[[], Any] = (self._parts[0] if len(self._parts) == 1
                                       else self._run_parts)

    def _run_parts(self) -> Any:
        result = None
        for part in self._parts:
            result = part()
        return result


def _compile(run: Sequence[tuple[Any, tuple]]) -> Callable[[], Any]:
    """One generated function for consecutive kernels, bound to its table and extras."""
    writer = _Writer()
    calls = []
    guarded = False
    for step in run:
        kernel, args = step
        if not isinstance(kernel, numba.core.registry.CPUDispatcher):
            raise TypeError(f"CompiledProgram: a step's kernel must be a numba.njit function, "
                            f"received {type(kernel).__name__}")
        call = f"{writer.name('_k', kernel)}(" + ", ".join(map(writer.expression, args)) + ")"
        if isinstance(step, Guard):
            guarded = True
            call = f"if not {call}:\n        return False"
        calls.append(call)
    if guarded:  # a guarded program returns a bool
        last = [f"    {calls[-1]}", "    return True"]
    else:
        last = [f"    return {calls[-1]}"]
    body = writer.lines + [f"    {c}" for c in calls[:-1]] + last
    source = "def program(table, extra):\n" + "\n".join(body) + "\n"
    names = tuple(sorted(writer.names.items()))
    key = (source, tuple(id(v) for _, v in names))
    dispatcher = _PROGRAMS.get(key)
    if dispatcher is None:
        dispatcher = _PROGRAMS[key] = _load(source, dict(names))
    table = np.array(writer.addresses, dtype=np.int64)
    extra = tuple(writer.extra)
    signature = (numba.typeof(table), numba.typeof(extra))
    overload = dispatcher.compile(signature)
    call = functools.partial(overload, table, extra)
    call.arrays = writer.arrays  # type: ignore[attr-defined]  # kept alive with the call
    return call


def _program_dir() -> Path:
    configured = os.environ.get("GO2_WBC_PROGRAM_DIR")
    base = Path(configured) if configured else Path.home() / ".cache" / "go2-wbc" / "programs"
    try:
        base.mkdir(parents=True, exist_ok=True)
        if os.access(base, os.W_OK):
            return base
    except OSError:
        pass
    fallback = Path(tempfile.gettempdir()) / "go2-wbc-programs"
    fallback.mkdir(parents=True, exist_ok=True)
    return fallback


def _kernel_files(values: Any) -> set[str]:
    """The module files of these kernels and of the kernels they call (one level down)."""
    files: set[str] = set()
    for value in values:
        function = getattr(value, "py_func", None)
        if function is None:
            continue
        callees = [v for v in function.__globals__.values() if hasattr(v, "py_func")]
        for kernel in (function, *(c.py_func for c in callees)):
            if os.path.isfile(kernel.__code__.co_filename):  # a module imported by path too
                files.add(kernel.__code__.co_filename)
    return files


def _load(source: str, names: dict[str, Any]) -> Any:
    """The generated source as a module file (numba caches only functions with a file),
    its names filled in, ``program`` compiled with numba's disk cache."""
    digest = hashlib.sha1(source.encode())
    for name in sorted(names):
        function = getattr(names[name], "py_func", None)
        if function is not None:
            digest.update(f"{name}={function.__module__}.{function.__qualname__}".encode())
    # An edited kernel, or a kernel it calls, is new code: numba would not notice.
    for module_file in sorted(_kernel_files(names.values())):
        stat = os.stat(module_file)
        digest.update(f"{module_file}:{stat.st_mtime_ns}:{stat.st_size}".encode())
    module_name = f"go2_wbc_program_{digest.hexdigest()[:20]}"
    path = _program_dir() / f"{module_name}.py"
    header = ('"""A compiled tick program generated by wbc.core.compiled_program."""\n'
              "from numba import carray\n\n\n")
    if not path.exists():
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(header + source)
        os.replace(temporary, path)
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    module.__dict__.update(names)
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    module.__dict__.update(names)
    sys.modules[module_name] = module
    # numba's cache cannot reload code that calls a kernel of a module it cannot import by
    # name (one loaded from its path): such a program is compiled in each process.
    importable = all(_importable(getattr(v, "py_func", None)) for v in names.values())
    return numba.njit(cache=importable)(module.program)


def _importable(function: Any) -> bool:
    """Whether a kernel's module is importable by its name (``None``: not a kernel)."""
    if function is None:
        return True
    module = sys.modules.get(function.__module__)
    return module is not None and module.__dict__ is function.__globals__
