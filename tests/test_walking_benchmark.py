"""``python -m benchmarks.walking``: what it measures from a walk's trace (synthetic traces of
known velocity), its report's tables, and a short walk run as the benchmark runs it."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from benchmarks.walking import (
    PUSH_RECOVERY_S,
    PUSH_WINDOW_S,
    SETTLE_INTO_WALK_S,
    WalkRun,
    measure,
    push_instants,
    run_standing,
    run_walk,
)
from benchmarks.walking_lockstep import lockstep
from benchmarks.walking_report import format_report, tracking_error

RATE_HZ = 1000


def trace(forward: float, lateral: float, yaw_rate: float, *, walk_s: float = 3.0,
          height_m: float = 0.32, fall: bool = False) -> dict[str, np.ndarray]:
    """0.5 s starting, ``walk_s`` walking at the given velocity (heading frame, from a
    heading of 30 deg), 0.5 s stopping; ``fall``: the base ends on the ground."""
    n = round(RATE_HZ * (1.0 + walk_s))
    t = np.arange(n) / RATE_HZ
    phase = np.where(t < 0.5, "starting", np.where(t < 0.5 + walk_s, "walking", "stopping"))
    heading = math.radians(30) + yaw_rate * t
    q = np.zeros((n, 19))
    q[:, 2] = height_m
    if fall:
        q[-200:, 2] = 0.1
    q[:, 5], q[:, 6] = np.sin(heading / 2), np.cos(heading / 2)
    v = np.zeros((n, 18))
    v[:, 0], v[:, 1], v[:, 5] = forward, lateral, yaw_rate  # base frame: level, so heading
    estimate = v.copy()
    estimate[:, 0] += 0.01
    return {"t_s": t, "phase": phase, "q_true": q, "v_true": v, "q": q.copy(), "v": estimate}


def test_the_mean_velocity_error_and_drift_are_measured_over_the_steady_walk():
    out = measure(trace(0.45, 0.0, 0.02), (0.5, 0.0, 0.0))
    np.testing.assert_allclose(out["measured"], [0.45, 0.0, 0.02], atol=1e-12)
    np.testing.assert_allclose(out["estimated"], [0.46, 0.0, 0.02], atol=1e-12)
    np.testing.assert_allclose(out["relative_error"], [-0.1, 0.0, 0.02], atol=1e-12)
    steady_s = 3.0 - SETTLE_INTO_WALK_S - 1e-3
    assert out["steady_s"] == pytest.approx(steady_s)
    assert out["yaw_drift_deg"] == pytest.approx(math.degrees(0.02 * steady_s))
    assert out["height_mean_m"] == pytest.approx(0.32) and out["height_range_mm"] == 0.0
    assert not out["fell"] and out["walking_s"] == pytest.approx(3.0 - 1e-3)


def test_a_turn_s_drift_is_its_heading_change_less_the_command():
    out = measure(trace(0.0, 0.0, 0.9), (0.0, 0.0, 1.0))
    assert out["relative_error"][2] == pytest.approx(-0.1)
    assert out["yaw_drift_deg"] == pytest.approx(math.degrees(-0.1 * out["steady_s"]))
    assert tracking_error({"command": [0.0, 0.0, 1.0], "relative_error":
                           out["relative_error"]}) == "yaw rate -10.0 %"


def test_a_fall_and_a_walk_too_short_to_measure_are_said():
    assert measure(trace(0.5, 0.0, 0.0, fall=True), (0.5, 0.0, 0.0))["fell"]
    short = measure(trace(0.5, 0.0, 0.0, walk_s=0.8), (0.5, 0.0, 0.0))
    assert short["steady_s"] == 0.0 and all(math.isnan(x) for x in short["measured"])


def test_push_instants_are_seeded_and_leave_time_to_recover():
    instants = push_instants(8, 8.0)
    assert instants == push_instants(8, 8.0) and len(set(instants)) == 8
    assert all(PUSH_WINDOW_S[0] <= x <= min(PUSH_WINDOW_S[1], 8.0 - PUSH_RECOVERY_S)
               for x in instants)
    assert instants != push_instants(8, 8.0, seed=1)


def _report() -> dict:
    walk = measure(trace(0.45, 0.0, 0.02), (0.5, 0.0, 0.0))
    row = {"name": "forward 0.5 m/s", "command": [0.5, 0.0, 0.0], "state": "estimate",
           "status": "SUCCEEDED", "message": "walk done", "control_rate_hz": 1000.0, **walk}
    aborted = {**row, "state": "truth", "status": "ABORTED", "message": "aborted: a fault"}
    stats = {"median": 120.0, "p99": 300.0, "mean": 130.0, "samples": 10}
    cpu = {"median": 100.0, "p99": 150.0, "mean": 105.0, "samples": 10}
    return {"machine": {"cpu": "cpu", "cores": 2, "load_average_1_5_15_min": [3.0, 2, 1],
                        "python": "3.11", "versions": {"mujoco": "4.0.0"}},
            "mode": "quick", "walk_s": 3.0, "settle_into_walk_s": 1.0, "tracking": [row, aborted],
            "pushes": {"impulse_ns": 5.0, "duration_s": 0.1, "speed_mps": 0.5, "seed": 31,
                       "walk_s": 4.0, "fell": 0,
                       "runs": [{"direction_deg": 90, "at_s": 2.1, **row}]},
            "timing": {"control_rate_hz": 1000.0, "walk_s": 3.0, "runs": [
                {"state": "estimate", "status": "SUCCEEDED", "fell": False,
                 "real_time_factor": 2.5, "sim_over_cpu": 2.8, "cpu_share": 0.9, "sim_s": 3.9,
                 "lockstep": {"turn_ticks": 100, "turns": 20,
                              "walking_us": {"controller": stats, "tick": stats},
                              "standing_us": {"controller": cpu, "tick": cpu},
                              "turn_ratios": {"controller": [1.1, 1.2, 1.3],
                                              "tick": [2.0, 2.5, 3.0]}},
                 "walking_ticks_cpu_us": {"controller": cpu, "tick": cpu},
                 "standing_real_time_factor": 5.0, "standing_sim_over_cpu": 6.0,
                 "rounds": [{"walking": 2.5, "standing": 5.0}, {"walking": 2.0, "standing": 5.0},
                            {"walking": 3.0, "standing": 4.0}]}]}}


def test_the_report_has_a_row_per_run_with_units():
    text = format_report(_report())
    assert "load 3.00 at start" in text
    row = next(line for line in text.splitlines() if line.startswith("forward 0.5 m/s"))
    assert row.split() == ["forward", "0.5", "m/s", "estimate", "1000", "SUCCEEDED", "no", "0.450",
                           "0.000", "0.020", "forward", "-10.0", "%", "+2.3", "0.320", "0"]
    assert "[m/s]" in text and "[rad/s]" in text and "[deg]" in text
    assert "  forward 0.5 m/s on the truth at 1000 Hz: ABORTED: aborted: a fault" in text
    assert "Pushes of 5 N s (50 N for 0.1 s)" in text and "fell in 0 of 1" in text
    rows = [line.split() for line in text.splitlines() if line.startswith("estimate  ")]
    assert rows == [["estimate", "controller", "120.0", "300.0", "100.0", "150.0", "100.0",
                     "150.0", "1.10-1.20-1.30"],
                    ["estimate", "tick", "120.0", "300.0", "100.0", "150.0", "100.0", "150.0",
                     "2.00-2.50-3.00"]]
    assert ("estimate: walking 2.50 (3 rounds 2.00-3.00; sim time over CPU time 2.80, cpu "
            "share 0.90, SUCCEEDED); standing 5.00 (4.00-5.00; over CPU time 6.00); "
            "walking/standing per round 0.40-0.75") in text


def test_a_report_of_some_parts_has_only_their_tables():
    report = _report()
    del report["tracking"], report["pushes"]
    text = format_report(report)
    assert "walking forward 0.5 m/s for 3 s and standing, in lockstep" in text
    assert "Speed tracking" not in text and "Pushes of" not in text


@pytest.mark.slow  # a loop built and 2 s walked: several seconds
def test_a_short_walk_runs_timed_and_measured_as_the_benchmark_runs_it():
    out = run_walk(WalkRun((0.5, 0.0, 0.0), 2.0), clock=time.thread_time)
    assert out["status"] == "SUCCEEDED" and not out["fell"]
    assert out["walking_s"] > 1.5 and out["steady_s"] > 0.5
    assert abs(out["relative_error"][0]) < 0.3  # a 2 s walk: near its command
    ticks = out["walking_ticks_us"]
    assert ticks["controller"]["samples"] == ticks["tick"]["samples"] > 1000
    assert 0 < ticks["controller"]["median"] < ticks["tick"]["median"]
    plain = run_walk(WalkRun((0.5, 0.0, 0.0), 1.0), traced=False)
    assert plain["status"] == "SUCCEEDED" and not plain["fell"]
    assert plain["real_time_factor"] > 0 and "measured" not in plain
    standing = run_standing("truth", 0.2, clock=time.thread_time)
    assert standing["ticks_us"]["tick"]["samples"] == 200
    assert standing["ticks_us"]["estimator"]["median"] < 20  # the truth: nothing to estimate
    turns = lockstep(WalkRun((0.5, 0.0, 0.0), 1.0).episode(), settle_s=0.3, walk_s=1.0,
                     turn_ticks=50)
    assert turns["turns"] >= 8 and turns["standing_us"]["tick"]["samples"] == 1000
    assert 0.5 < turns["turn_ratios"]["tick"][1] < 20
