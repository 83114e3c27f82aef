"""The pieces of a control tick timed one by one (:class:`TimedTicks`), for the loop benchmark."""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Iterator, Sequence
from typing import Any

import mujoco
import numpy as np

from sim.control_loop import ControlLoop

#: Parts of a tick, in the order the loop runs them (``rest`` is split around physics).
PARTS = ("sensors", "estimator", "actions", "controller", "rest", "physics")


class TimedTicks:
    """The pieces of ``ControlLoop.spin_once``, called in its order and timed one by one.

    While :meth:`timing_mj_step` is active, ``mujoco.mj_step`` is wrapped to time each call
    (about 0.1 us added to ``physics``), so that ``physics.mj_step`` is the steps the loop
    really took, with the caches as the tick left them.
    """

    def __init__(self, loop: ControlLoop):
        self.loop = loop
        self.samples: dict[str, list[float]] = {p: [] for p in (*PARTS, "tick")}
        self.stages: dict[str, list[float]] = {}
        self.mj_step: list[float] = []
        self._stepped = 0.0  # seconds in mj_step since the last tick began

    @contextlib.contextmanager
    def timing_mj_step(self) -> Iterator[None]:
        """Time every ``mujoco.mj_step`` call inside the block."""
        step, clock = mujoco.mj_step, time.perf_counter

        def timed(*args: Any, **kwargs: Any) -> None:
            start = clock()
            step(*args, **kwargs)
            self._stepped += clock() - start

        mujoco.mj_step = timed
        try:
            yield
        finally:
            mujoco.mj_step = step

    def __call__(self) -> None:
        loop, clock = self.loop, time.perf_counter
        robot, context = loop.robot, loop.context
        self._stepped = 0.0
        t0 = clock()
        now = robot.time_s
        if loop.estimator is None:
            q, v = robot.read_state()
            ts = clock()
        else:
            record = robot.read_sensors()
            ts = clock()
            q, v = loop.estimate_state(record)
        t1 = clock()
        context.observe(now, q, v)
        loop.runner.tick(now)
        t2 = clock()
        raw = loop.command(q, v)
        t3 = clock()
        out = loop.guard(raw, v)
        context.record_output(out)
        loop.last_output = out
        t4 = clock()
        robot.write_command(out)
        t5 = clock()
        for hook in loop.hooks:
            hook(loop, out)
        t6 = clock()
        for part, seconds in zip(PARTS, (ts - t0, t1 - ts, t2 - t1, t3 - t2,
                                         (t4 - t3) + (t6 - t5), t5 - t4)):
            self.samples[part].append(seconds)
        self.samples["tick"].append(t6 - t0)
        self.mj_step.append(self._stepped)
        for stage, seconds in raw.timings.items():
            self.stages.setdefault(stage, []).append(seconds)

    def breakdown(self) -> dict[str, dict[str, float]]:
        """Per-part statistics [us]; ``controller.<stage>`` and ``physics.mj_step`` below."""
        out = {part: stats_us(self.samples[part])
               for part in ("sensors", "estimator", "actions", "controller")}
        out.update({f"controller.{k}": stats_us(v) for k, v in self.stages.items()})
        out["physics"] = stats_us(self.samples["physics"])
        out["physics.mj_step"] = stats_us(self.mj_step)
        out["rest"] = stats_us(self.samples["rest"])
        out["tick"] = stats_us(self.samples["tick"])
        around = np.subtract(self.samples["tick"], self.samples["controller"])
        out["around controller"] = stats_us(around)
        return out

def stats_us(seconds: Sequence[float]) -> dict[str, float]:
    """Median, p99 and mean [us] of ``seconds``, and how many."""
    values = np.asarray(seconds, dtype=float) * 1e6
    if values.size == 0:
        return {"median": math.nan, "p99": math.nan, "mean": math.nan, "samples": 0}
    return {"median": float(np.median(values)), "p99": float(np.percentile(values, 99)),
            "mean": float(values.mean()), "samples": int(values.size)}
