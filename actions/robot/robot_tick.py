"""The stages of the robot loop's one tick (:meth:`~actions.robot.robot_loop.RobotLoop.tick`),
and what a loop passes to it: a timer that marks each stage's end, filters that may take over
the decision, relays run after the write.

The tick, in stages (each :class:`Stage` ends with ``timer.mark(stage)``):

- sense: ``READ`` the robot's sensors (or its exact state, ``state="truth"``); ``ESTIMATE``:
  the state estimator's tick and the behaviours' view of the state (``context.observe``);
- decide: ``ACTIONS``: the action runner's tick; ``CONTROLLER``: the controller, or the
  fallback while the state cannot be trusted (:mod:`actions.robot.state_fallback`);
  ``GUARD``: the command's checks (a command a driver would refuse is replaced by the safe
  one) and the output's bookkeeping;
- act: ``WRITE`` the command to the robot; ``RELAY``: the loop's relays (a DDS action bridge's
  poll); ``HOOKS``: the loop's tick hooks (metrics, logs).

The simulated loop ticks with no timer and no filter; the wall-clock loop
(:class:`~actions.robot.realtime_loop.RealtimeLoop`) with its stage timer, its staleness
watchdog and its rest sequence as filters, its DDS action bridge as a relay; the loop
benchmark (:class:`benchmarks.timed_ticks.TimedTicks`) with its own timer.
"""

from __future__ import annotations

import enum
import time
from collections.abc import Callable
from typing import Protocol

from wbc.robot_io.motor_command import MotorCommand


class Stage(enum.IntEnum):
    """A stage of the tick, in order (module doc)."""

    READ = 0
    ESTIMATE = 1
    ACTIONS = 2
    CONTROLLER = 3
    GUARD = 4
    WRITE = 5
    RELAY = 6
    HOOKS = 7


class TickTimer(Protocol):
    """Told when a tick starts and when each of its stages ends."""

    def start(self) -> None:
        """The tick starts."""

    def mark(self, stage: Stage) -> None:
        """``stage`` ended (stages a tick skips end at once, in order)."""


class Untimed:
    """A :class:`TickTimer` that keeps nothing (the simulated loop's)."""

    def start(self) -> None:
        """Nothing to keep."""

    def mark(self, stage: Stage) -> None:
        """Nothing to keep."""


#: The timer of an untimed tick.
UNTIMED = Untimed()


class StageTimes:
    """A :class:`TickTimer` that keeps, on ``clock`` [s], the tick's start and each stage's end.

    Args:
        clock: A monotonic clock [s] (``time.perf_counter``).
    """

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self._clock = clock
        #: When the tick started [s].
        self.started_s = 0.0
        #: When each :class:`Stage` ended [s], indexed by the stage.
        self.ends_s = [0.0] * len(Stage)

    def start(self) -> None:
        """Keep the start."""
        self.started_s = self._clock()

    def mark(self, stage: Stage) -> None:
        """Keep ``stage``'s end."""
        self.ends_s[stage] = self._clock()

    def seconds(self, first: Stage, last: Stage | None = None) -> float:
        """Time [s] from the end of the stage before ``first`` (or the start) to the end of
        ``last`` (default ``first``)."""
        begin = self.started_s if first == 0 else self.ends_s[first - 1]
        return self.ends_s[first if last is None else last] - begin


class TickFilter(Protocol):
    """What a loop adds to the tick between sensing and deciding (the wall-clock loop's
    staleness watchdog and its rest sequence)."""

    def sensed(self, now_s: float, fresh: bool) -> MotorCommand | None:
        """After the sense stage at robot time ``now_s`` [s] (``fresh``: a new sample came):
        a command that replaces this tick's decision (no actions, no controller, no hooks),
        or ``None`` to decide. Every filter is told, in order; the first command wins."""

    def stale(self, now_s: float) -> str:
        """In the decide stage, before the controller: why the state is stale ('' when not);
        the loop then falls back (:mod:`actions.robot.state_fallback`)."""
