"""Per-tick timing of a wall-clock control loop: each stage's time, the tick's CPU time, its
latency and its wake-up lateness, summarised over the run and over the last second.

Series (all in seconds per tick): the stages ``read`` (take the state and estimate),
``actions`` (the action runner's tick), ``controller`` (the QP, the command guard),
``write`` (build and publish the command), ``bridge`` (poll the DDS action bridge), ``hooks``
(the loop's tick hooks: logging), ``gc`` (Python's garbage collection, run after the command
is written: :mod:`actions.robot.idle_collector`); ``tick`` (the whole tick, wall clock),
``cpu`` (the CPU time the loop's thread spent in it, ``time.thread_time``), ``latency`` (from
the start of reading the state to the command's publication), ``wake`` (how late the wait
for the deadline ended) and ``align`` (how long the tick then waited for the robot's state to
arrive: see :mod:`actions.robot.realtime_loop`).

Whole-run percentiles come from a histogram with bins 2 % wide (so they are within 2 %);
means and maxima are exact. The last second's figures come from a ring of its ticks.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np

from wbc.core.errors import ConfigurationError

#: The stages of a tick, in order.
STAGES = ("read", "actions", "controller", "write", "bridge", "hooks", "gc")
#: Every series recorded per tick: the stages, then the whole-tick figures.
SERIES = (*STAGES, "tick", "cpu", "latency", "wake", "align")
_LOW_S = 1e-7  # the histogram's first bin holds everything at or below 0.1 us
_RATIO = 1.02
_BINS = math.ceil(math.log(10.0 / _LOW_S) / math.log(_RATIO))  # up to 10 s


@numba.njit(numba.void(numba.float64[::1], numba.int64[:, ::1], numba.float64[::1],
                       numba.float64[::1], numba.float64[:, ::1], numba.int64), cache=True)
def _accumulate(times_s, hist, sums, maxima, ring, ring_row):
    """Add one tick's times [s] to the histograms, sums, maxima and the ring's row
    ``ring_row`` (one compiled call: the loop pays it every tick, after the tick)."""
    log_low, per_log = math.log(_LOW_S), 1.0 / math.log(_RATIO)
    for k in range(times_s.shape[0]):
        t = times_s[k]
        b = int((math.log(max(t, _LOW_S)) - log_low) * per_log)
        hist[k, min(b, _BINS - 1)] += 1
        sums[k] += t
        maxima[k] = max(maxima[k], t)
        ring[ring_row, k] = t


class TickStats:
    """Accumulates :data:`SERIES` and the tick counters of a run.

    Args:
        window_ticks: Ticks in the recent window (a second's worth: the control rate).
    """

    def __init__(self, window_ticks: int) -> None:
        n = len(SERIES)
        self._hist = np.zeros((n, _BINS), dtype=np.int64)
        self._sum = np.zeros(n)
        self._max = np.zeros(n)
        self._ring = np.zeros((max(1, int(window_ticks)), n))
        self._ring_used = 0
        self._ring_next = 0
        #: Ticks run.
        self.ticks = 0
        #: Ticks that ran past the next deadline.
        self.misses = 0
        #: Ticks that found no fresh state.
        self.no_fresh_state = 0
        #: Times the staleness watchdog sent the safe command after fresh states.
        self.watchdog_trips = 0

    def add(self, times_s: np.ndarray, *, fresh: bool, missed: bool) -> None:
        """Record one tick: ``times_s`` (len(SERIES),) [s]; whether it had a fresh state and
        whether it overran the next deadline."""
        times = np.ascontiguousarray(times_s, dtype=np.float64)
        if times.shape != self._sum.shape:  # the kernel indexes without bounds checks
            raise ConfigurationError(f"times_s: expected {len(SERIES)} times [s] ({SERIES}), "
                                     f"received shape {np.shape(times_s)}")
        self.ticks += 1
        self.misses += missed
        self.no_fresh_state += not fresh
        _accumulate(times, self._hist, self._sum, self._max, self._ring, self._ring_next)
        self._ring_next = (self._ring_next + 1) % len(self._ring)
        self._ring_used = min(self._ring_used + 1, len(self._ring))

    def summary(self) -> dict[str, dict[str, float]]:
        """Per series, over the run: ``mean_ms``, ``p50_ms``, ``p99_ms``, ``max_ms``."""
        out: dict[str, dict[str, float]] = {}
        count = max(self.ticks, 1)
        for k, name in enumerate(SERIES):
            out[name] = {"mean_ms": self._sum[k] / count * 1e3,
                         "p50_ms": self._percentile(k, 0.50) * 1e3,
                         "p99_ms": self._percentile(k, 0.99) * 1e3,
                         "max_ms": self._max[k] * 1e3}
        return out

    def recent(self, name: str, percent: float) -> float:
        """The ``percent`` percentile [s] of series ``name`` over the recent window."""
        if not self._ring_used:
            return math.nan
        return float(np.percentile(self._ring[:self._ring_used, SERIES.index(name)], percent))

    def report(self) -> dict[str, Any]:
        """Counters and :meth:`summary`, for a JSON report."""
        return {"ticks": self.ticks, "deadline_misses": self.misses,
                "no_fresh_state_ticks": self.no_fresh_state,
                "watchdog_trips": self.watchdog_trips, "series": self.summary()}

    def _percentile(self, row: int, fraction: float) -> float:
        counts = self._hist[row]
        total = int(counts.sum())
        if not total:
            return math.nan
        k = int(np.searchsorted(np.cumsum(counts), fraction * total))
        # The bin's geometric middle, capped by the exact maximum.
        return min(_LOW_S * _RATIO ** (k + 0.5), float(self._max[row]))
