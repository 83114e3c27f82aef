"""Fixed-period deadlines on a monotonic clock: sleep until just before each one, then spin.

``time.sleep`` wakes tens of microseconds late at best (Linux's default timer slack is 50 us)
and far later on a loaded machine; sleeping until ``spin_s`` before the deadline and spinning
on the clock for the rest puts the median wake at the deadline. A tick that runs past the next
deadline is a miss: it is counted and the next tick starts at once, with the grid re-anchored
there. Missed ticks are never made up in a burst (a burst would answer stale states
back-to-back).
"""

from __future__ import annotations

import time
from collections.abc import Callable

from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real

#: Default spin before each deadline [s]: the median wake lands on the deadline.
DEFAULT_SPIN_S = 2e-4


class DeadlineClock:
    """Deadlines every ``period_s`` on ``clock``.

    Args:
        period_s: The period [s] (2 ms: 500 Hz).
        clock: A monotonic clock [s] (``time.monotonic``); injectable for tests.
        sleep: Sleeps for a duration [s] (``time.sleep``); injectable for tests.
        spin_s: How long before a deadline [s] to stop sleeping and spin on the clock
            (0: sleep all the way).

    Raises:
        ConfigurationError: A period that is not a positive number of seconds, or a spin that
            is negative or not shorter than the period.

    Example:
        >>> deadlines = DeadlineClock(0.002)
        >>> deadlines.start()
        >>> while running:
        ...     deadlines.wait()        # returns how late it woke [s]
        ...     tick()
        ...     deadlines.tick_done()   # True if the tick overran the next deadline
    """

    def __init__(self, period_s: float, *, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep,
                 spin_s: float = DEFAULT_SPIN_S) -> None:
        if not is_finite_real(period_s) or period_s <= 0.0:
            raise ConfigurationError(
                f"period_s: expected a number of seconds > 0, received {period_s!r}")
        if not is_finite_real(spin_s) or not 0.0 <= spin_s < period_s:
            raise ConfigurationError(
                f"spin_s: expected seconds in [0, period_s = {period_s:g}), received "
                f"{spin_s!r}")
        self.period_s = float(period_s)
        self.spin_s = float(spin_s)
        self._clock = clock
        self._sleep = sleep
        self._deadline = 0.0
        #: Ticks that ran past the next deadline.
        self.misses = 0
        #: Ticks that started on a deadline (counted by :meth:`wait`).
        self.ticks = 0

    @property
    def deadline_s(self) -> float:
        """The next deadline [s, on the clock]."""
        return self._deadline

    def start(self) -> None:
        """Make now the first deadline."""
        self._deadline = self._clock()

    def wait(self) -> float:
        """Wait for the next deadline; return how late [s] the wait ended (>= 0)."""
        deadline = self._deadline
        clock = self._clock
        remaining = deadline - self.spin_s - clock()
        if remaining > 0.0:
            self._sleep(remaining)
        now = clock()
        while now < deadline:  # the last spin_s: the median wake lands on the deadline
            now = clock()
        self.ticks += 1
        return now - deadline

    def shift(self, delta_s: float) -> None:
        """Move the current deadline, and so the grid after it, by ``delta_s`` [s] (positive:
        later): how a loop keeps its phase to another clock's (a robot's states)."""
        self._deadline += delta_s

    def time_left_s(self) -> float:
        """Seconds from now to the end of this tick's period (the deadline
        :meth:`tick_done` schedules next); negative once it has passed."""
        return self._deadline + self.period_s - self._clock()

    def tick_done(self) -> bool:
        """Schedule the next deadline one period on; return whether the tick missed it.

        On a miss the next deadline is now: the next tick starts at once, and the ones after
        it keep the period from there.
        """
        self._deadline += self.period_s
        now = self._clock()
        if now <= self._deadline:
            return False
        self.misses += 1
        self._deadline = now
        return True
