"""Runs a robot loop (:class:`~actions.robot.robot_loop.RobotLoop`) on the wall clock: a robot
on DDS.

Deadlines and alignment around the loop's one tick: each tick waits for its deadline
(:class:`~actions.robot.deadline_clock.DeadlineClock`: 500 Hz by default, never bursting
after a miss) and for the robot's state, then runs the loop's
:meth:`~actions.robot.robot_loop.RobotLoop.tick` with a stage timer
(:mod:`actions.robot.tick_stats`), two filters (the staleness watchdog,
:class:`~actions.robot.state_watchdog.StateWatchdog`, and the stop phases of
:mod:`actions.robot.rest_sequence`) and the DDS action bridge's poll as a relay; then its
callbacks and Python's garbage collection.

Phase: a robot sends its states on its own clock, at the same rate. Ticking just before a
state arrives would answer every state a period late (and miss some). So, when the robot can
say whether a state is waiting
(:class:`~actions.robot.robot_capabilities.StateWaiting`, as
:class:`~actions.robot.dds_robot.DdsRobot` can), each tick first waits up to ``align_s`` (by
default :data:`DEFAULT_ALIGN_SHARE` of the period) for one, and the deadlines follow the
states: later by the time waited (at most :data:`ALIGN_FOLLOW_S` a tick), or, when a state was
already there, earlier by :data:`ALIGN_STEP_S` to find the arrival again. The tick then starts
within tens of microseconds of the state's arrival. A state that comes late (the robot's own
jitter) is still answered in its tick, on arrival, instead of being overtaken by the next one
and skipped; it moves the grid by :data:`ALIGN_FOLLOW_S` only, so the states after it, on time
again, are not answered late. A robot whose states stop or come slower than the loop (more
than :data:`ALIGN_PAUSE_SHARE` of the waits of :data:`ALIGN_WINDOW_S` in vain) pauses the
alignment for :data:`ALIGN_PAUSE_S`; the loop then ticks on its own deadlines.

Staleness: one limit, ``stale_after_s``, for two clocks. The estimator distrusts a robot that
sends nothing new (``trust_timeout_s`` of ticks without a sample); it counts control periods,
and a loop that misses deadlines takes longer than that. The watchdog here counts wall time:
no fresh state for ``stale_after_s``. Either makes the loop fall back
(:mod:`actions.robot.state_fallback`): the running goal ends ABORTED with the reason, the held
torques decay to pure joint damping, and once fresh trustworthy states return a ``stand``
goal stands the robot up before goals are accepted again. The loop sets the estimator's
``trust_timeout_s`` to ``stale_after_s``, whose default is the robot's own
(:class:`~actions.robot.robot_capabilities.StalenessLimited`: a
:class:`~actions.robot.dds_robot.DdsRobot`'s, from the rate measured at start: 40 ms at
500 Hz, 100 ms at 200 Hz), else the estimator's.
"""

from __future__ import annotations

import contextlib
import math
import signal
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from actions.robot.deadline_clock import DEFAULT_SPIN_S, DeadlineClock
from actions.robot.idle_collector import IdleCollector
from actions.robot.rest_sequence import Phase, RestSequence, RestSettings
from actions.robot.robot_capabilities import (
    CountsSkips,
    ReportsStats,
    SkipCounters,
    StalenessLimited,
    StateWaiting,
)
from actions.robot.robot_tick import Stage, StageTimes
from actions.robot.state_watchdog import StateWatchdog
from actions.robot.tick_stats import SERIES, TickStats
from wbc.controller.control_output import ControlOutput
from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real

if TYPE_CHECKING:
    from actions.robot.robot_loop import RobotLoop

#: A fixed wait [s] for the robot's state after a deadline (a quarter of a 500 Hz period).
DEFAULT_ALIGN_S = 5e-4
#: The default wait for the robot's state after a deadline, as a share of the period: a late
#: state is still answered in its tick, which then ends within the period.
DEFAULT_ALIGN_SHARE = 0.5
#: How much earlier [s] the next deadline is when the state was there before this one.
ALIGN_STEP_S = 2e-5
#: The most [s] the deadlines move later in one tick to follow a state that came during the
#: wait (a late one moves them no more: jitter, not a new phase).
ALIGN_FOLLOW_S = 1e-4
#: Share of the ticks of :data:`ALIGN_WINDOW_S` [s] whose wait for a state may end in vain
#: before the alignment pauses for :data:`ALIGN_PAUSE_S` [s] (a robot slower than the loop,
#: or silent: each vain wait idles ``align_s`` of the period).
ALIGN_PAUSE_SHARE, ALIGN_WINDOW_S, ALIGN_PAUSE_S = 0.2, 0.1, 2.0
(_READ, _ACTIONS, _CONTROLLER, _WRITE, _BRIDGE, _HOOKS, _GC, _TICK, _CPU, _LATENCY, _WAKE,
 _ALIGN) = range(len(SERIES))
# The tick's stages by plain index (an enum member looked up on its class is slow).
_END_ESTIMATE, _END_ACTIONS, _END_GUARD, _END_WRITE, _END_RELAY = (
    Stage.ESTIMATE, Stage.ACTIONS, Stage.GUARD, Stage.WRITE, Stage.RELAY)


class RealtimeLoop:
    """A control loop ticking on the wall clock, with its stop phases and timing.

    Args:
        loop: The control loop, on a robot whose ``time_s`` is the wall clock (a
            :class:`~actions.robot.dds_robot.DdsRobot`), estimating its state.
        rate_hz: Ticks per second; the controller's period must be ``1 / rate_hz``.
        bridge: A DDS action bridge to poll each tick (not also as a loop hook).
        stale_after_s: The limit [s] without a fresh state, the watchdog's and the
            estimator's (see the module doc); ``None``: the robot's, else the estimator's.
        align_s: Longest wait [s] for the robot's state after each deadline (see the module
            doc); 0 ticks on the deadlines alone; ``None``: :data:`DEFAULT_ALIGN_SHARE` of
            the period.
        rest: How the robot is stood up at the start and brought to rest at the end.
        clock, sleep, spin_s: The deadlines' clock, sleep and spin (see
            :class:`~actions.robot.deadline_clock.DeadlineClock`); injectable for tests.
        timer: The stage timer [s] (``time.perf_counter``).
        cpu_clock: The thread's CPU time [s] (``time.thread_time``).

    Raises:
        ConfigurationError: A loop without an estimator, a rate its controller is not
            configured for, or an invalid limit.
    """

    def __init__(self, loop: RobotLoop, *, rate_hz: float = 500.0, bridge: Any = None,
                 stale_after_s: float | None = None, rest: RestSettings | None = None,
                 align_s: float | None = None,
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep, spin_s: float = DEFAULT_SPIN_S,
                 timer: Callable[[], float] = time.perf_counter,
                 cpu_clock: Callable[[], float] = time.thread_time) -> None:
        if loop.estimator is None:
            raise ConfigurationError(
                "loop: a wall-clock loop estimates its state; build it with state='estimate'")
        if not is_finite_real(rate_hz) or rate_hz <= 0.0:
            raise ConfigurationError(f"rate_hz: expected a rate > 0 [Hz], received {rate_hz!r}")
        period = loop.controller.control_period_s
        if abs(period * rate_hz - 1.0) > 1e-9:
            raise ConfigurationError(
                f"rate_hz: the controller runs every {period:g} s ({1.0 / period:g} Hz), the "
                f"loop was asked for {rate_hz:g} Hz; build the controller with "
                f"control_period_s={1.0 / rate_hz:g}")
        robot = loop.robot.robot  # the robot itself, behind its MappedRobot
        config = loop.estimator.config
        if stale_after_s is None:  # the robot's measured limit, else the estimator's
            stale_after_s = (robot.stale_after_s if isinstance(robot, StalenessLimited)
                             else config.trust_timeout_s)
        if not is_finite_real(stale_after_s) or stale_after_s <= 0.0:
            raise ConfigurationError(
                f"stale_after_s: expected seconds > 0, received {stale_after_s!r}")
        if config.trust_timeout_s != stale_after_s:
            # One limit: the estimator's trust limit is the watchdog's.
            loop.estimator.config = replace(config, trust_timeout_s=float(stale_after_s))
        if align_s is None:
            align_s = DEFAULT_ALIGN_SHARE / rate_hz
        if not is_finite_real(align_s) or not 0.0 <= align_s < 1.0 / rate_hz:
            raise ConfigurationError(
                f"align_s: expected seconds in [0, the period {1.0 / rate_hz:g}), received "
                f"{align_s!r}")
        self.loop = loop
        self.rate_hz = float(rate_hz)
        #: Waits for the robot's next state (``None``: the robot cannot, or no alignment).
        self._state_wait: Callable[[float], bool] | None = (
            robot.wait_for_new_state if align_s > 0.0 and isinstance(robot, StateWaiting)
            else None)
        self.align_s = float(align_s)
        #: Ticks whose wait for a state ended in vain; times the alignment paused.
        self.align_timeouts = 0
        self.align_pauses = 0
        self._align_window = (0, 0)  # (ticks, timeouts) at the start of this window
        self._align_paused_until = -math.inf
        self.bridge = bridge
        self.stale_after_s = float(stale_after_s)
        self.deadlines = DeadlineClock(1.0 / rate_hz, clock=clock, sleep=sleep, spin_s=spin_s)
        self.stats = TickStats(window_ticks=round(rate_hz))
        #: The staleness watchdog (built from a sample, or WAITING: damping).
        self.watchdog = StateWatchdog(self.stale_after_s, since_s=loop.robot.time_s,
                                      robot=robot, stats=self.stats)
        #: Python's garbage collection, at the end of each tick while :meth:`run` runs.
        self.collector = IdleCollector()
        self._collecting = False
        self.rest = RestSequence(loop, rest)
        #: The tick's filters and relays (module doc), and its stage timer.
        self._filters = (self.watchdog, self.rest)
        self._relays = () if bridge is None else (bridge.poll,)
        self._marks = StageTimes(timer)
        #: Called every tick, in the hooks stage, with this object (logs, status).
        self.callbacks: list[Callable[[RealtimeLoop], None]] = []
        self._clock = clock
        self._timer = timer
        self._cpu = cpu_clock
        self._robot = robot
        #: This tick's times [s] by :data:`~actions.robot.tick_stats.SERIES` (being filled).
        self.times = np.zeros(len(SERIES))
        #: The previous tick's times [s], complete.
        self.last_times = np.full(len(SERIES), math.nan)
        #: The last tick's command (``None`` while damping).
        self.last_output: ControlOutput | None = None
        #: Whether the last tick overran the next deadline.
        self.missed = False
        self._started = False
        self._status_mark = (math.nan, 0, 0, 0)
        #: The robot's skipped states when the first tick had read, if it counts them
        #: (:class:`~actions.robot.robot_capabilities.CountsSkips`; those before the first
        #: tick are the start-up's, not the loop's).
        self._robot_counters: SkipCounters | None = (
            robot.counters if isinstance(robot, CountsSkips) else None)
        self._skipped_at_start: int | None = None

    # -- running ----------------------------------------------------------------------------

    def start(self) -> None:
        """Stand the robot if it is down (see :class:`RestSettings`), start the deadlines."""
        if not self._started:
            self._started = True
            self.rest.stand_if_down()
            self.deadlines.start()
            self._status_mark = (self.loop.robot.time_s, 0, 0, 0)

    def request_stop(self, reason: str) -> None:
        """Bring the robot to rest and stop (a second request: damp now). Any thread."""
        self.rest.request_stop(reason)

    @property
    def done(self) -> bool:
        """The stop phases are over: the loop may exit."""
        return self.rest.phase is Phase.DONE

    def run(self, *, duration_s: float | None = None) -> None:
        """Tick until stopped and at rest; ``duration_s`` [s] of robot time requests the stop.

        An exception from a tick sends the damping command once, then propagates. Python's
        garbage collection runs at the end of the ticks, not wherever an allocation starts
        it (:class:`~actions.robot.idle_collector.IdleCollector`).
        """
        self.start()
        end = math.inf if duration_s is None else self.loop.robot.time_s + duration_s
        asked = False
        with self.collector:
            self._collecting = True
            try:
                while not self.done:
                    if not asked and self.loop.robot.time_s >= end:
                        asked = True
                        self.request_stop(f"duration {duration_s:g} s elapsed")
                    self.tick()
            finally:
                self._collecting = False

    @property
    def fresh(self) -> bool:
        """The last tick had a fresh state."""
        return self.watchdog.fresh

    def tick(self) -> None:
        """Wait for the deadline and the robot's state, run the loop's tick, its callbacks
        and the garbage collection, account for it."""
        if not self._started:
            self.start()
        wake_s = self.deadlines.wait()
        align_s = self._align()
        marks, timer, times = self._marks, self._timer, self.times
        self.last_times[:] = times
        c0 = self._cpu()
        try:
            self.last_output = self.loop.tick(marks, self._filters, self._relays)
            if self._skipped_at_start is None:
                self._skipped_at_start = self._robot_skipped()
            for callback in self.callbacks:
                callback(self)
            t_hooks = timer()
            if self._collecting:  # in the time left before the next deadline
                self.collector.collect(self.deadlines.time_left_s())
            t_gc = timer()
        except BaseException:
            with contextlib.suppress(Exception):  # the tick's own error is the one to raise
                self.loop.robot.write_command(self.rest.damping)
            raise
        ends, t0 = marks.ends_s, marks.started_s
        times[_READ] = ends[_END_ESTIMATE] - t0
        times[_ACTIONS] = ends[_END_ACTIONS] - ends[_END_ESTIMATE]
        times[_CONTROLLER] = ends[_END_GUARD] - ends[_END_ACTIONS]
        times[_WRITE] = ends[_END_WRITE] - ends[_END_GUARD]
        times[_BRIDGE] = ends[_END_RELAY] - ends[_END_WRITE]
        times[_HOOKS], times[_GC] = t_hooks - ends[_END_RELAY], t_gc - t_hooks
        times[_TICK], times[_CPU] = t_gc - t0, self._cpu() - c0
        times[_LATENCY], times[_WAKE], times[_ALIGN] = ends[_END_WRITE] - t0, wake_s, align_s
        self.missed = self.deadlines.tick_done()
        self.stats.add(times, fresh=self.fresh, missed=self.missed)

    def _align(self) -> float:
        """Wait for the robot's state, move the deadlines to it (module doc); the wait [s]."""
        wait = self._state_wait
        now = self.loop.robot.time_s
        if wait is None or now < self._align_paused_until:
            return 0.0
        waited = 0.0
        if wait(0.0):
            self.deadlines.shift(-ALIGN_STEP_S)  # it was there: look for its arrival earlier
        else:
            t0 = self._clock()  # the deadlines' clock: the shift is in its seconds
            arrived = wait(self.align_s)
            waited = self._clock() - t0
            if arrived:  # the state comes later in the period: follow it, a step at a time
                self.deadlines.shift(min(waited, ALIGN_FOLLOW_S))
            else:
                self.align_timeouts += 1
        ticks, timeouts = self._align_window
        window = ALIGN_WINDOW_S * self.rate_hz
        if self.stats.ticks - ticks >= window:
            if self.align_timeouts - timeouts > ALIGN_PAUSE_SHARE * window:
                self.align_pauses += 1
                self._align_paused_until = now + ALIGN_PAUSE_S
            self._align_window = (self.stats.ticks, self.align_timeouts)
        return waited

    def _robot_skipped(self) -> int:
        """The robot's ``counters.ticks_skipped`` (0 when it does not count them)."""
        counters = self._robot_counters
        return 0 if counters is None else counters.ticks_skipped

    # -- reporting --------------------------------------------------------------------------

    def goal_text(self) -> str:
        """The running goal and its status (``idle`` when none)."""
        goals = self.loop.runner.active_goals()
        if not goals:
            return "idle"
        return f"{goals[0].label} {goals[0].status.name}"

    def status_line(self) -> str:
        """One line on the last interval: tick rate, misses, no-state ticks, own tick
        latency, the goal, the controller's status. Resets the interval."""
        now, stats = self.loop.robot.time_s, self.stats
        since, ticks, misses, stale = self._status_mark
        self._status_mark = (now, stats.ticks, stats.misses, stats.no_fresh_state)
        elapsed = now - since
        rate = (stats.ticks - ticks) / elapsed if elapsed > 0 else math.nan
        out = self.last_output
        if out is None:
            control, phase = "motors damping", ""
        else:
            control = out.status.name + (f" ({out.message[:60]})" if out.message else "")
            phase = "" if self.rest.phase is Phase.RUNNING else f" | {self.rest.phase.name}"
        return (f"t {now:7.1f} s | {rate:6.1f} Hz | misses {stats.misses - misses} | "
                f"no state {stats.no_fresh_state - stale} | latency p50 "
                f"{stats.recent('latency', 50) * 1e3:.2f} ms p99 "
                f"{stats.recent('latency', 99) * 1e3:.2f} ms | cpu p99 "
                f"{stats.recent('cpu', 99) * 1e3:.2f} ms | {self.goal_text()} | {control}"
                f"{phase}")

    @property
    def state_ticks_skipped(self) -> int:
        """The robot's states no tick read, counted from the first tick (two came within one
        tick: the older is skipped); the robot's own ``ticks_skipped`` also counts those sent
        while the loop was being built."""
        skipped = self._robot_skipped()
        return skipped - (skipped if self._skipped_at_start is None else self._skipped_at_start)

    def report(self) -> dict[str, Any]:
        """The run's figures for a JSON report: rate, counters, per-stage timing [ms], the
        robot's counters, how it stopped, every goal's terminal event."""
        robot = self._robot
        robot_stats = robot.stats() if isinstance(robot, ReportsStats) else {}
        ended = ("succeeded", "canceled", "aborted", "rejected")
        return {
            "rate_hz": self.rate_hz, "duration_s": self.loop.robot.time_s,
            "stale_after_s": self.stale_after_s, **self.stats.report(),
            "state_ticks_skipped": self.state_ticks_skipped, "robot": robot_stats,
            "gc": self.collector.report(),
            "align": {"max_wait_s": self.align_s, "active": self._state_wait is not None,
                      "timeouts": self.align_timeouts, "pauses": self.align_pauses},
            "stop": {"reason": self.rest.stop_reason, "phase": self.rest.phase.name,
                     "notes": self.rest.notes},
            "modes": [t.as_dict() for t in self.loop.fallback.log.transitions],
            "goals": [{"t_s": t, "goal_id": goal_id, "event": event, "detail": str(detail)}
                      for t, goal_id, event, detail in self.loop.runner.event_log
                      if event in ended],
        }


@contextlib.contextmanager
def stop_on_signals(loop: RealtimeLoop,
                    signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)) -> Iterator[None]:
    """While the block runs, SIGINT (Ctrl-C) and SIGTERM ask ``loop`` to come to rest (a
    second one: damp now) instead of raising; the previous handlers come back after.

    Call it on the main thread (Python runs signal handlers there).
    """
    def handler(signum: int, frame: object) -> None:
        loop.request_stop(signal.Signals(signum).name)

    previous = {sig: signal.signal(sig, handler) for sig in signals}
    try:
        yield
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)
