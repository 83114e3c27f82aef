"""What a task a user adds costs the tick: written in NumPy, with its own compiled kernel, and
a built-in task of the same size, against the default controller, in one process.

``python -m benchmarks.qp_timing_tasks [--ticks N] [--rounds R]``: four controllers stand
on the same states (the standing pose, a slowly varying velocity), taking turns every
``ticks`` ticks for ``rounds`` rounds so that they see the same machine; it prints each
one's median ``step`` time, its difference to the default controller's, and the number of
calls the tick's program makes (1: one compiled call).
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from tasks.frame_position_task import FramePositionTask
from tasks.task import Task
from wbc.controller.whole_body_controller import WholeBodyController

_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "custom_task.py"


def _example() -> object:
    spec = importlib.util.spec_from_file_location("custom_task_example", _EXAMPLE)
    module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
    spec.loader.exec_module(module)  # type: ignore[union-attr]
    return module


def controllers() -> dict[str, WholeBodyController]:
    """The default controller, and with a base-height task in NumPy, compiled, built in."""
    example = _example()
    made: dict[str, WholeBodyController] = {}
    tasks: dict[str, Callable[[WholeBodyController], Task] | None] = {
        "default": None,
        "+ base height, NumPy (examples/custom_task.py)": lambda c: example.BaseHeightTask(),
        "+ base height, own kernel (CompiledBaseHeightTask)":
            lambda c: example.CompiledBaseHeightTask(),
        "+ base height, built in (FramePositionTask, z)":
            lambda c: FramePositionTask(c.model, "base", axes="z", kp=100.0, weight=200.0),
    }
    for name, make in tasks.items():
        controller = WholeBodyController()
        q = controller.description.pose("standing")
        task = None if make is None else controller.add_task(make(controller))
        controller.reset(q)
        if task is not None:
            target = float(q[2]) if isinstance(task, example.BaseHeightTask) else q[2:3].copy()
            task.set_target(target)
        made[name] = controller
    return made


def run(*, ticks: int = 500, rounds: int = 10) -> list[dict[str, float | str | int]]:
    """Median tick [us] of each controller, interleaved; see the module docstring."""
    made = controllers()
    q = next(iter(made.values())).description.pose("standing")
    nv = 18
    phases = np.linspace(0.0, 2.0 * np.pi, nv, endpoint=False)
    samples: dict[str, list[float]] = {name: [] for name in made}
    for r in range(rounds + 1):  # the first round warms up
        for name, controller in made.items():
            for k in range(ticks):
                v = 0.02 * np.sin(phases + 1e-3 * k)
                start = time.perf_counter()
                controller.step(q, v)
                if r:
                    samples[name].append(time.perf_counter() - start)
    base = float(np.median(samples["default"]))
    rows: list[dict[str, float | str | int]] = []
    for name, controller in made.items():
        builder = controller.builder
        median = float(np.median(samples[name]))
        rows.append({"controller": name, "median_us": 1e6 * median,
                     "added_us": 1e6 * (median - base),
                     "program_calls": builder.plan.last_program.calls})
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=500, help="ticks a turn")
    parser.add_argument("--rounds", type=int, default=10, help="turns of each controller")
    args = parser.parse_args(argv)
    for row in run(ticks=args.ticks, rounds=args.rounds):
        print(f"{row['controller']:52s} median {row['median_us']:7.1f} us  "
              f"added {row['added_us']:+6.1f} us  program calls {row['program_calls']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
