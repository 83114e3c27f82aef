"""The wall-clock loop's tick statistics: one compiled call a tick, the same figures as the
plain NumPy definition (histogram percentiles within a bin, exact means and maxima)."""

from __future__ import annotations

import numpy as np
import pytest

from actions.robot.tick_stats import SERIES, TickStats
from wbc.core.errors import ConfigurationError


def test_the_summary_is_within_a_bin_of_the_exact_figures() -> None:
    rng = np.random.default_rng(4)
    times = rng.lognormal(np.log(4e-4), 0.6, size=(3000, len(SERIES)))
    times[17, 3] = 0.0  # below the first bin: counted in it
    stats = TickStats(window_ticks=500)
    for k, row in enumerate(times):
        stats.add(row, fresh=k % 7 != 0, missed=k % 50 == 0)
    assert (stats.ticks, stats.misses, stats.no_fresh_state) == (3000, 60, 429)
    summary = stats.summary()
    for k, name in enumerate(SERIES):
        column = times[:, k]
        figures = summary[name]
        assert figures["mean_ms"] == pytest.approx(column.mean() * 1e3, rel=1e-12)
        assert figures["max_ms"] == column.max() * 1e3
        for key, percent in (("p50_ms", 50), ("p99_ms", 99)):
            assert figures[key] == pytest.approx(np.percentile(column, percent) * 1e3, rel=0.02)
    recent = times[-500:, SERIES.index("tick")]
    assert stats.recent("tick", 99) == pytest.approx(np.percentile(recent, 99), rel=1e-12)


def test_a_row_of_the_wrong_length_is_refused_and_counts_nothing() -> None:
    stats = TickStats(window_ticks=10)
    with pytest.raises(ConfigurationError, match=r"^times_s: expected 12 times"):
        stats.add(np.zeros(len(SERIES) + 1), fresh=True, missed=False)
    assert stats.ticks == 0 and np.isnan(stats.summary()["tick"]["p50_ms"])
