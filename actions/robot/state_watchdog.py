"""The wall-clock loop's staleness watchdog (:class:`StateWatchdog`), a filter of the robot
loop's tick (:class:`~actions.robot.robot_tick.TickFilter`): no fresh state for
``stale_after_s`` of wall time makes the loop fall back (:mod:`actions.robot.state_fallback`).

The estimator distrusts a robot that sends nothing new too, but it counts control periods
(``trust_timeout_s`` of ticks without a sample), and a loop that misses deadlines takes longer
than that; the watchdog counts the robot's clock.
"""

from __future__ import annotations

from actions.robot.state_fallback import stream_note
from actions.robot.tick_stats import TickStats
from wbc.robot_io.motor_command import MotorCommand


class StateWatchdog:
    """Whether the robot's state is fresh, tick by tick.

    Args:
        stale_after_s: Longest time [s] without a fresh state.
        since_s: When [s, the robot's clock] the last fresh state came (the loop was built).
        robot: The robot itself, to say what its stream brought
            (:func:`~actions.robot.state_fallback.stream_note`).
        stats: Where its trips are counted (``watchdog_trips``).
    """

    def __init__(self, stale_after_s: float, *, since_s: float, robot: object,
                 stats: TickStats) -> None:
        self.stale_after_s = float(stale_after_s)
        #: The last tick had a fresh state.
        self.fresh = False
        self._last_fresh_s = since_s
        self._robot = robot
        self._stats = stats
        self._stale = False

    def sensed(self, now_s: float, fresh: bool) -> MotorCommand | None:
        """Keep when the last fresh state came; never replaces the decision (``None``)."""
        self.fresh = fresh
        if fresh:
            self._last_fresh_s = now_s
        return None

    def stale(self, now_s: float) -> str:
        """Why the state is stale after ``stale_after_s`` without a fresh one ('' when it is
        not); the first tick of each stale spell counts a trip."""
        stale_s = now_s - self._last_fresh_s
        if stale_s <= self.stale_after_s:
            self._stale = False
            return ""
        if not self._stale:
            self._stale = True
            self._stats.watchdog_trips += 1
        return (f"watchdog: no fresh robot state for {stale_s * 1e3:.0f} ms (limit "
                f"{self.stale_after_s * 1e3:g} ms)" + stream_note(self._robot))
