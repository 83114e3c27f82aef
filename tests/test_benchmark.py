"""benchmarks.qp_timing --quick: the report's structure, the JSON file and the plot.

The quick run (~35 s: every backend on recorded states and a timed episode) is in the slow
stage (``make test-slow``); the quick stage checks the backends against DAQP
(tests/test_whole_body_controller.py) and runs a benchmark end to end (tests/test_sweep.py).
"""

from __future__ import annotations

import ctypes
import json
import platform

import pytest

from benchmarks import qp_timing
from wbc import available_backends
from wbc.backends import missing_backends

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bench")
    json_path, png_path = folder / "report.json", folder / "timing.png"
    assert qp_timing.main(["--quick", "--json", str(json_path), "--plot", str(png_path)]) == 0
    return json.loads(json_path.read_text()), png_path


@pytest.mark.slow
def test_machine_block(quick_run):
    report, _ = quick_run
    machine = report["machine"]
    assert machine["cpu"] and machine["cores"] >= 1
    assert machine["python"] == platform.python_version()
    for package in ("pin", "placo", "mujoco", "daqp", "osqp", "qpsolvers", "numpy"):
        assert machine["versions"][package], package
    assert report["mode"] == "quick"
    assert report["episode"]["warmup_ticks_excluded"] == 200


@pytest.mark.slow
def test_every_backend_has_numbers_or_a_skip_reason(quick_run):
    report, _ = quick_run
    rows = {row["name"]: row for row in report["backends"]}
    expected = {"default (daqp)", "daqp, full QP", "placo", *available_backends(),
                *missing_backends()}
    assert set(rows) == expected
    for name, row in rows.items():
        if name in missing_backends():
            assert row["skipped"], name
            continue
        assert row["skipped"] is None, (name, row["skipped"])
        assert row["ticks"] == 1000, name
        assert 0 < row["median_us"] <= row["p90_us"] <= row["p99_us"] <= row["max_us"], name
        assert len(row["total_samples_us"]) == row["ticks"]
        assert row["ratio_to_placo"] > 0 and row["cpu_ratio_to_placo"] > 0
        assert 0 < row["cpu_median_us"] < 10 * row["max_us"]
        assert isinstance(row["failures"], int) and 0.0 < row["cpu_share"] <= 1.5
        if row["failures"] < row["ticks"]:
            # Tight-tolerance solvers: a solution that breaks its own constraints is a bug.
            assert row["max_eq_violation"] < 1e-5 and row["max_ineq_violation"] < 1e-5, name
    assert rows["placo"]["ratio_to_placo"] == pytest.approx(1.0)
    h2h = report["head_to_head"]
    assert h2h["block_ticks"] == 100
    assert h2h["median_ratio"] == pytest.approx(h2h["default"]["median"] / h2h["placo"]["median"])
    low, mid, high = h2h["block_ratio_p10_p50_p90"]
    assert 0 < low <= mid <= high
    assert rows["placo"]["stage_median_us"]["assembly"] is None
    assert rows["daqp"]["failures"] == 0
    assert rows["daqp, full QP"]["failures"] == 0


@pytest.mark.slow
def test_recorded_states_replay_every_controller_alike(quick_run):
    report, _ = quick_run
    recorded = report["recorded"]
    assert set(recorded["rows"]) == {"default", "daqp-hot (reduced QP)", "daqp (full QP)",
                                     "placo"}
    for name, row in recorded["rows"].items():
        assert row["ticks"] == recorded["ticks"] > 500, name
        assert 0 < row["median_us"] <= row["p90_us"] <= row["p99_us"], name


@pytest.mark.slow
def test_scaling_and_episode_tables(quick_run):
    report, _ = quick_run
    scenarios = {(row["controller"], row["scenario"]) for row in report["scaling"]}
    assert len(scenarios) == 6
    for row in report["scaling"]:
        assert row["ticks"] == 200 and row["median_us"] > 0 and row["cpu_median_us"] > 0
        # Measured in turns of 50 ticks against PlaCo on the same scenario.
        assert row["block_ticks"] == 50
        placo = next(r for r in report["scaling"]
                     if r["controller"] == "placo" and r["scenario"] == row["scenario"])
        assert row["ratio_to_placo"] == pytest.approx(row["median_us"] / placo["median_us"])
        low, mid, high = row["block_ratio_p10_p50_p90"]
        assert 0 < low <= mid <= high
        if row["controller"] == "placo":
            assert low == mid == high == pytest.approx(1.0)
    metrics = report["episode_table"]["metrics"]
    for key in ("raised_foot_rms_mm", "raised_foot_max_mm", "holding_rms_mm",
                "holding_max_mm", "stance_sliding_max_mm", "stance_travel_max_mm",
                "min_stance_normal_force_n", "min_com_margin_mm", "max_base_tilt_deg",
                "max_torque_fraction", "max_torque_jump_nm", "qp_failures", "real_time_factor"):
        assert isinstance(metrics[key], (int, float)), key
    # The default controller lifts the foot and balances: loose bounds that still fail on a
    # fall, a dropped foot or a saturated motor.
    assert metrics["lift_completed"] is True and metrics["fell"] is False
    assert metrics["qp_failures"] == 0
    assert metrics["raised_foot_max_mm"] < 20.0
    assert metrics["min_stance_normal_force_n"] > 0.0
    assert metrics["max_base_tilt_deg"] < 5.0
    assert metrics["max_torque_fraction"] < 0.9


@pytest.mark.slow
def test_plot_is_a_png(quick_run):
    _, png_path = quick_run
    assert png_path.read_bytes()[:8] == PNG_SIGNATURE


def test_c_stdout_silenced_discards_c_output_inside_the_block_only(capfd):
    libc = ctypes.CDLL(None)
    print("before", flush=True)
    with qp_timing.c_stdout_silenced():
        libc.printf(b"from C inside\n")
    libc.printf(b"from C after\n")
    libc.fflush(None)
    out = capfd.readouterr().out
    assert "from C inside" not in out
    assert "before" in out and "from C after" in out
