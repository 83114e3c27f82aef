"""Python's cyclic garbage collector run in a loop's idle time: :class:`IdleCollector`.

CPython collects when allocations pass a threshold, wherever that allocation happens: inside
a QP, a DDS write, the middle of a tick. In the controller process a collection of the
middle generation took 0.5 to 1.4 ms (measured over a whole run, start-up included), more
than the idle time of a 1 kHz tick. Inside the loop collections are rare (the ticks allocate
few objects the collector tracks: 6 young collections in 55 s at 1 kHz, 0.05 ms the
longest), but each would land in some tick. The wall-clock loops therefore turn automatic
collection off while they run and collect at the end of each tick, after the command is
written, what CPython would have collected (the oldest generation over its threshold), when
the time left before the next deadline fits that generation's recent longest collection.
One that does not fit is postponed (a younger generation is collected in its place, if one
fits); one postponed too long (:data:`OVERDUE_FACTOR` times its threshold) runs anyway, so
memory stays bounded.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Callable
from typing import Any

#: A generation whose count reaches this many times its threshold is collected even when it
#: does not fit the time left.
OVERDUE_FACTOR = 4
#: Each generation's expected collection time is its longest recent one: the longest seen,
#: decaying by this factor at each of its collections (an early outlier fades out).
DECAY = 0.9
GENERATIONS = 3


class IdleCollector:
    """A context manager: automatic garbage collection off inside the block (as it was
    after it); :meth:`collect` at the end of each tick.

    Args:
        clock: The clock [s] of the durations (``time.perf_counter``).
    """

    def __init__(self, *, clock: Callable[[], float] = time.perf_counter) -> None:
        self._clock = clock
        #: Collections run, by generation.
        self.collections = [0] * GENERATIONS
        #: The longest collection seen [s], by generation.
        self.longest_s = [0.0] * GENERATIONS
        #: Times the due generation did not fit and waited; times one ran although it did
        #: not fit (overdue).
        self.postponed = 0
        self.forced = 0
        self._expected_s = [0.0] * GENERATIONS
        self._was_enabled = False

    def __enter__(self) -> IdleCollector:
        self._was_enabled = gc.isenabled()
        gc.disable()
        return self

    def __exit__(self, *exc: object) -> None:
        if self._was_enabled:
            gc.enable()

    @staticmethod
    def due() -> int | None:
        """The generation CPython would collect now (the oldest over its threshold), or
        ``None`` (also when the thresholds turn collection off: a first threshold of 0)."""
        return _oldest_due(gc.get_count(), gc.get_threshold())

    def collect(self, time_left_s: float) -> float:
        """Collect the due generation if it fits ``time_left_s`` [s] (or is overdue), else
        the oldest younger one that fits; the time spent [s]."""
        counts, thresholds = gc.get_count(), gc.get_threshold()
        generation = _oldest_due(counts, thresholds)
        if generation is None:
            return 0.0
        if counts[generation] >= OVERDUE_FACTOR * thresholds[generation]:
            if self._expected_s[generation] > time_left_s:
                self.forced += 1
        elif self._expected_s[generation] > time_left_s:
            self.postponed += 1
            fitting = [g for g in range(generation) if self._expected_s[g] <= time_left_s]
            if not fitting:
                return 0.0
            generation = fitting[-1]
        start = self._clock()
        gc.collect(generation)
        spent = self._clock() - start
        self.collections[generation] += 1
        self.longest_s[generation] = max(self.longest_s[generation], spent)
        self._expected_s[generation] = max(spent, DECAY * self._expected_s[generation])
        return spent

    def report(self) -> dict[str, Any]:
        """Collections and the longest [ms] by generation, postponed and forced counts."""
        return {"collections": list(self.collections),
                "longest_ms": [round(s * 1e3, 3) for s in self.longest_s],
                "postponed": self.postponed, "forced": self.forced}


def _oldest_due(counts: tuple[int, ...], thresholds: tuple[int, ...]) -> int | None:
    """The oldest generation whose count is over its threshold (``None``: none, or a first
    threshold of 0, CPython's "never")."""
    if thresholds[0] == 0:
        return None
    for generation in reversed(range(GENERATIONS)):
        if counts[generation] > thresholds[generation]:
            return generation
    return None
