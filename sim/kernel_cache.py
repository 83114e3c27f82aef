"""Whether numba's on-disk cache holds the control loop's compiled kernels: a cold cache means
the next run compiles them first (about a minute on 2 cores), and the command line says so."""

from __future__ import annotations

import importlib
from collections.abc import Sequence
from typing import IO

from numba.core.registry import CPUDispatcher

#: The modules whose kernels every simulated run compiles (``cache=True``): the model's
#: kinematics, the tasks and constraints, the QP, the motor command, both estimators' shared
#: kernels, the simulated sensors.
LOOP_KERNEL_MODULES = (
    "wbc.model.kinematics_kernels", "tasks.task_kernels", "tasks.constraint_kernels",
    "wbc.controller.qp_kernel", "wbc.controller.cost_kernels",
    "wbc.controller.motor_command_shaper", "wbc.estimation.shared_kernels", "sim.sensors",
)
NOTICE = ("compiling the controller's kernels once, about a minute (numba's cache is cold: a "
          "first run, or the kernels changed); later runs start in seconds")


def _cached_overloads(dispatcher: CPUDispatcher) -> int:
    """How many compiled versions of ``dispatcher`` numba's cache holds for its source as it
    is now (numba drops an index whose source file changed); -1 when it cannot tell."""
    try:
        return len(dispatcher._cache._cache_file._load_index())  # numba 0.62's FunctionCache
    except (AttributeError, OSError, EOFError, ValueError):
        return -1


def cold_modules(modules: Sequence[str] = LOOP_KERNEL_MODULES) -> list[str]:
    """The ``modules`` none of whose cached kernels numba's cache holds (imports them).

    A module with one cached kernel or more is warm: some kernels compile only in some runs
    (the other estimator, a fault), so one missing kernel does not make a cold start.
    """
    cold = []
    for name in modules:
        module = importlib.import_module(name)
        counts = [_cached_overloads(value) for value in vars(module).values()
                  if isinstance(value, CPUDispatcher) and value.__module__ == name]
        if counts and all(count == 0 for count in counts):
            cold.append(name)
    return cold


def notice_if_cold(stream: IO[str], modules: Sequence[str] | None = None) -> bool:
    """Print :data:`NOTICE` (one line) to ``stream`` when one of ``modules`` (default
    :data:`LOOP_KERNEL_MODULES`) is cold; returns whether it did."""
    cold = cold_modules(LOOP_KERNEL_MODULES if modules is None else modules)
    if cold:
        print(f"go2-wbc: {NOTICE}", file=stream, flush=True)
    return bool(cold)
