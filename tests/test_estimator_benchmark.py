"""benchmarks.estimator --quick: every state source's rows, their bounds, the costs.

In the slow stage (``make test-slow``, ~40 s): the quick stage bounds every estimator's
estimate in closed loop (tests/test_realistic_plant.py, test_invariant_ekf.py).
"""

from __future__ import annotations

import json

import pytest

from benchmarks import estimator
from wbc.estimation.estimators import ESTIMATORS

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    path = tmp_path_factory.mktemp("estimator") / "report.json"
    assert estimator.main(["--quick", "--json", str(path)]) == 0
    return json.loads(path.read_text())


def test_every_source_runs_every_scenario(quick):
    rows = quick["rows"]
    assert [(r["scenario"], r["source"]) for r in rows] == [
        (scenario, source) for scenario in ("high five, 1000 Hz", "pushes (1)",
                                            "standing 10 s")
        for source in ("truth", *ESTIMATORS)]
    for row in rows:
        assert row["status"] in ("SUCCEEDED", "STANDING"), row


def test_the_truth_has_no_estimate_error_and_the_estimators_are_accurate(quick):
    for row in quick["rows"]:
        if row["source"] == "truth":
            assert row["estimate_velocity_rms_m_s"] == 0.0 and row["estimate_height_max_mm"] == 0
            continue
        assert 0.0 < row["estimate_velocity_rms_m_s"] <= 0.02, row
        assert 0.0 < row["estimate_height_max_mm"] <= 3.0, row
        assert row["estimate_roll_max_deg"] <= 0.3 and row["estimate_pitch_max_deg"] <= 0.3
        assert row["estimate_horizontal_drift_max_mm"] <= 10.0, row
        if row["scenario"].startswith("high five"):
            assert row["raised_foot_rms_mm"] <= 5.0 and row["holding_rms_mm"] <= 3.0


def test_each_estimator_is_timed_on_the_same_records(quick):
    costs = quick["cost"]
    assert [c["estimator"] for c in costs] == list(ESTIMATORS)
    assert len({c["updates"] for c in costs}) == 1 and costs[0]["updates"] > 5000
    for cost in costs:
        assert 0.0 < cost["median_us"] <= cost["p99_us"] < 1e4


def test_the_printed_report_has_the_table_and_the_costs(quick):
    text = estimator.format_report(quick)
    assert "scenario" in text and "v RMS" in text and "[mm/s]" in text
    assert "Cost of update() alone on a recorded high five's sensor records:" in text
