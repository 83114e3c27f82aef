"""The control tick timed stage by stage (:class:`TimedTicks`), for the loop benchmark: the
robot loop's own tick (:meth:`actions.robot.robot_loop.RobotLoop.tick`) with this benchmark's
timer."""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import mujoco
import numpy as np

from actions.robot.robot_tick import Stage, StageTimes
from sim.control_loop import ControlLoop

#: Parts of a tick, in the order the loop runs them (``rest`` is split around physics).
PARTS = ("sensors", "estimator", "actions", "controller", "rest", "physics")
# The stages by plain name (an enum member looked up on its class is slow in Python 3.11).
_READ, _ESTIMATE, _ACTIONS, _CONTROLLER, _GUARD, _WRITE, _RELAY, _HOOKS = Stage


class TimedTicks:
    """``ControlLoop.spin_once``'s tick, with a timer that marks each stage's end.

    The parts, from the tick's stages (:class:`~actions.robot.robot_tick.Stage`):
    ``sensors`` is ``READ``, ``estimator`` ``ESTIMATE``, ``actions`` ``ACTIONS``,
    ``controller`` ``CONTROLLER``, ``physics`` ``WRITE``, ``rest`` ``GUARD`` with ``RELAY``
    and ``HOOKS``. While :meth:`timing_mj_step` is active, ``mujoco.mj_step`` is wrapped to
    time each call (about 0.1 us added to ``physics``), so that ``physics.mj_step`` is the
    steps the loop really took, with the caches as the tick left them.
    """

    def __init__(self, loop: ControlLoop, *, clock: Callable[[], float] = time.perf_counter):
        """Args:
            loop: The loop whose ticks to time.
            clock: What marks the stages [s]: the wall clock, or ``time.thread_time`` for
                the CPU time the tick's thread used (what a loaded machine's other
                processes do not add to).
        """
        self.loop = loop
        self.samples: dict[str, list[float]] = {p: [] for p in (*PARTS, "tick")}
        self.stages: dict[str, list[float]] = {}
        self.mj_step: list[float] = []
        self._stepped = 0.0  # seconds in mj_step since the last tick began
        self._marks = StageTimes(clock)

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
        """One tick of the loop, timed."""
        marks = self._marks
        self._stepped = 0.0
        out = self.loop.tick(marks)
        seconds = marks.seconds
        samples = self.samples
        samples["sensors"].append(seconds(_READ))
        samples["estimator"].append(seconds(_ESTIMATE))
        samples["actions"].append(seconds(_ACTIONS))
        samples["controller"].append(seconds(_CONTROLLER))
        samples["rest"].append(seconds(_GUARD) + seconds(_RELAY, _HOOKS))
        samples["physics"].append(seconds(_WRITE))
        samples["tick"].append(marks.ends_s[_HOOKS] - marks.started_s)
        self.mj_step.append(self._stepped)
        if out is not None:
            for stage, stage_s in out.timings.items():
                self.stages.setdefault(stage, []).append(stage_s)

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
