"""Python's garbage collection in a loop's idle time (:class:`IdleCollector`): off inside the
block, the due generation collected when it fits the time left, postponed or forced
otherwise."""

import gc
from collections.abc import Iterator

import pytest

from actions.robot.idle_collector import OVERDUE_FACTOR, IdleCollector

YOUNG = 50  # the young generation's threshold in these tests


class SteppingClock:
    """Each call returns ``step_s`` more than the last: every collection lasts ``step_s``."""

    def __init__(self, step_s: float) -> None:
        self.step_s = step_s
        self.now_s = 0.0

    def __call__(self) -> float:
        self.now_s += self.step_s
        return self.now_s


@pytest.fixture
def thresholds() -> Iterator[None]:
    """Small thresholds (50, 2, 2), automatic collection off; the interpreter's own
    afterwards. Each test starts with ``gc.collect()``: counts at zero."""
    before, enabled = gc.get_threshold(), gc.isenabled()
    gc.disable()
    gc.set_threshold(YOUNG, 2, 2)
    try:
        yield
    finally:
        gc.set_threshold(*before)
        if enabled:
            gc.enable()


def allocate(count: int) -> list[list[int]]:
    """``count`` objects the collector tracks, kept alive."""
    return [[k] for k in range(count)]


def test_collection_is_off_inside_the_block_and_as_before_after() -> None:
    enabled = gc.isenabled()
    try:
        for before in (True, False):
            (gc.enable if before else gc.disable)()
            with IdleCollector():
                assert not gc.isenabled()
            assert gc.isenabled() is before
    finally:
        (gc.enable if enabled else gc.disable)()


def test_the_due_generation_is_the_oldest_over_its_threshold(thresholds) -> None:
    gc.collect()
    assert IdleCollector.due() is None
    kept = allocate(2 * YOUNG)
    assert IdleCollector.due() == 0
    collector = IdleCollector(clock=SteppingClock(1e-4))
    assert collector.collect(time_left_s=1e-3) == pytest.approx(1e-4)
    assert gc.get_count()[1] == 1 and collector.collections == [1, 0, 0]  # one young one
    for _ in range(3):  # three young collections: the middle one is over its threshold
        kept += allocate(2 * YOUNG)
        gc.collect(0)
    kept += allocate(2 * YOUNG)
    assert IdleCollector.due() == 1
    collector.collect(time_left_s=1e-3)
    assert collector.collections == [1, 1, 0] and gc.get_count()[1] == 0
    assert collector.report() == {"collections": [1, 1, 0], "longest_ms": [0.1, 0.1, 0.0],
                                  "postponed": 0, "forced": 0}
    gc.set_threshold(0)  # the interpreter's "never"
    assert IdleCollector.due() is None and collector.collect(1.0) == 0.0


def test_a_collection_that_does_not_fit_waits_until_it_is_overdue(thresholds) -> None:
    gc.collect()
    collector = IdleCollector(clock=SteppingClock(2e-3))  # every collection lasts 2 ms
    kept = allocate(2 * YOUNG)
    collector.collect(time_left_s=5e-3)  # the first one: its length is not known yet
    kept += allocate(2 * YOUNG)
    assert collector.collect(time_left_s=1e-3) == 0.0  # 2 ms do not fit in 1
    assert collector.postponed == 1 and collector.collections == [1, 0, 0]
    kept += allocate(OVERDUE_FACTOR * YOUNG)  # four times its threshold: it runs anyway
    assert collector.collect(time_left_s=1e-3) == pytest.approx(2e-3)
    assert collector.forced == 1 and collector.collections == [2, 0, 0]
    assert len(kept) > 0


def test_a_younger_generation_that_fits_runs_in_place_of_one_that_does_not(thresholds) -> None:
    gc.collect()
    collector = IdleCollector(clock=SteppingClock(1e-4))
    kept = allocate(2 * YOUNG)
    collector.collect(time_left_s=1e-3)  # the young generation: 0.1 ms
    collector._clock = SteppingClock(3e-3)
    for _ in range(3):
        kept += allocate(2 * YOUNG)
        gc.collect(0)
    kept += allocate(2 * YOUNG)
    collector.collect(time_left_s=5e-3)  # the middle one: 3 ms
    for _ in range(3):
        kept += allocate(2 * YOUNG)
        gc.collect(0)
    kept += allocate(2 * YOUNG)
    assert IdleCollector.due() == 1
    collector._clock = SteppingClock(1e-4)
    collector.collect(time_left_s=1e-3)  # 3 ms expected: the young one instead
    assert collector.collections == [2, 1, 0] and collector.postponed == 1
    assert IdleCollector.due() == 1  # still due: the next tick with time collects it
