"""benchmarks.loop_timing --quick: the report's structure; every time positive and finite.

In the slow stage (``make test-slow``, ~25 s: four instrumented high fives); the quick stage
runs the tick's stages in tests/test_robot_tick.py and a benchmark end to end in
tests/test_sweep.py.
"""

from __future__ import annotations

import json
import math

import pytest

from benchmarks import loop_timing

pytestmark = pytest.mark.slow

PARTS = ("sensors", "estimator", "actions", "controller", "physics", "physics.mj_step", "rest",
         "tick", "around controller")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    path = tmp_path_factory.mktemp("loop") / "report.json"
    assert loop_timing.main(["--quick", "--json", str(path)]) == 0
    return json.loads(path.read_text())


def test_the_episode_is_the_command_lines_high_five(quick_run):
    episode = quick_run["episode"]
    assert quick_run["mode"] == "quick"
    assert episode["cli_defaults"] == {"target_height_m": 0.4, "hold_seconds": 2,
                                       "control_rate_hz": 1000.0}
    assert episode["target_height_m"] == 0.4 and episode["hold_seconds"] == 0
    assert episode["plant"] == "menagerie" and episode["settle_s"] == 0.3
    assert quick_run["machine"]["cores"] >= 1


def test_both_rates_run_the_goal_to_success_on_the_estimate_and_on_the_truth(quick_run):
    runs = quick_run["runs"]
    assert [r["name"] for r in runs] == ["1000 Hz, estimated", "1000 Hz, truth",
                                         "500 Hz, estimated", "500 Hz, truth"]
    for run, period, steps in zip(runs, (1e-3, 1e-3, 2e-3, 2e-3), (1, 1, 2, 2)):
        assert run["control_period_s"] == period and run["physics_steps_per_tick"] == steps
        assert run["status"] == run["instrumented"]["status"] == "SUCCEEDED"
        assert run["ticks"] == pytest.approx(run["sim_s"] / period, abs=1)
        assert run["instrumented"]["ticks"] == run["ticks"]  # the same episode, timed
        assert run["feedback_messages"] > 10
        assert 0.0 < run["real_time_factor"] < math.inf
        assert 0.0 < run["instrumented"]["real_time_factor"] < math.inf
        assert 0.0 < run["cpu_share"] <= 1.5
        assert run["real_time_factor"] == pytest.approx(run["sim_s"] / run["wall_s"])
    ratios = quick_run["estimate_over_truth_real_time_factor"]
    assert set(ratios) == {"1000 Hz", "500 Hz"}
    assert ratios["1000 Hz"] == pytest.approx(runs[0]["real_time_factor"]
                                              / runs[1]["real_time_factor"])


def test_every_part_of_the_tick_has_positive_finite_times(quick_run):
    for run in quick_run["runs"]:
        parts = run["per_tick_us"]
        stages = [p for p in parts if p.startswith("controller.")]
        assert "controller.total" in stages
        assert set(parts) == {*PARTS, *stages}
        for name, stats in parts.items():
            assert stats["samples"] == run["ticks"], name
            assert 0.0 < stats["median"] <= stats["p99"] < math.inf, name
            assert 0.0 < stats["mean"] < math.inf, name
        assert parts["physics.mj_step"]["median"] <= parts["physics"]["median"]
        assert parts["around controller"]["median"] < parts["tick"]["median"]
        if run["state"] == "estimate":  # the estimator's tick is a few microseconds
            assert parts["estimator"]["median"] >= 1.0


def test_the_printed_report_has_both_tables(quick_run):
    text = loop_timing.format_report(quick_run)
    assert "Whole episode (ControlLoop.spin_once)" in text
    assert "Per tick [us], 500 Hz, truth" in text and "  mj_step" in text
    assert "real-time factor on the estimate over the truth's: 1000 Hz " in text


def test_a_fresh_process_times_its_first_ticks_and_each_actions_first_goal(quick_run):
    fresh = quick_run["fresh_process"]
    assert list(fresh) == ["construction", "first ticks (standing)", "high_five",
                           "follow_joint_trajectory", "sit", "stand"]
    assert 0.0 < fresh["construction"]["wall_ms"] < math.inf
    assert fresh["first ticks (standing)"]["ticks"] == 300  # SETTLE_S at 1 kHz
    for part, stats in list(fresh.items())[1:]:
        assert stats["status"] == "SUCCEEDED", part
        assert stats["ticks"] > 0, part
        assert 0.0 < stats["median_us"] <= stats["p999_us"] <= stats["max_us"] < math.inf, part
