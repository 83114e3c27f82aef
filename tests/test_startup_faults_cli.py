"""``go2-wbc high-five`` with a sensor fault from t = 0 that leaves the estimator nothing to
start from (no sample, a NaN joint): one line says why the loop waits, the motors damp, the
estimator starts on the first usable sample, the robot is stood up, and the high five
SUCCEEDS (exit 0) with the report written. No traceback."""

from __future__ import annotations

import json

import pytest

from sim.cli import main
from sim.cli.exit_codes import EXIT_SUCCEEDED
from tests.sweeps import quick_first


def run_cli(tmp_path, capsys, fault: str) -> tuple[int, list[str], dict]:
    report = tmp_path / "report.json"
    code = main(["high-five", "--sensor-fault", fault, "--hold", "0", "--report", str(report)])
    lines = capsys.readouterr().out.splitlines()
    return code, lines, json.loads(report.read_text())


# The dropout in the quick stage, the joint reading in the slow one (``make test-slow``).
@pytest.mark.parametrize(("fault", "why"), quick_first([
    ("dropout,0,1", "no sensor sample"),
    ("joint_nan,0,1", "q: non-finite reading at FR_thigh_joint"),
], lambda case: case[0].startswith("dropout"), unpack=True))
def test_a_fault_from_the_start_waits_then_the_high_five_succeeds(tmp_path, capsys, fault, why):
    code, lines, report = run_cli(tmp_path, capsys, fault)
    assert code == EXIT_SUCCEEDED
    waiting = [line for line in lines if "not controlling" in line]
    assert waiting == [(f"[  0.000 s] not controlling: waiting for a sensor sample to start the "
                       f"state estimator from: {why}; the motors damp until it can")]
    assert report["result"]["status"] == "SUCCEEDED"
    modes = [(mode["mode"], mode["t_s"]) for mode in report["loop_modes"]]
    # Waiting for the fault's 1 s, then the stand (2 s), then control.
    assert modes == [("WAITING", 0.0), ("RECOVERING", 1.0), ("CONTROLLING", pytest.approx(3.0,
                                                                                         abs=0.01))]
    metrics = report["metrics"]
    assert metrics["max_base_tilt_deg"] < 1.0 and metrics["raised_foot_rms_mm"] < 5.0


def test_ticks_without_a_trustworthy_state_are_not_counted_as_qp_failures(tmp_path, capsys):
    """A stream stale for 0.2 s in the hold: the goal ends ABORTED (exit 1); the metrics count
    the damping tick apart, and no QP failed (before, it counted as one)."""
    report = tmp_path / "report.json"
    code = main(["high-five", "--sensor-fault", "stale,3.5,0.2", "--metrics", "--report",
                 str(report)])
    out = capsys.readouterr().out
    metrics = json.loads(report.read_text())["metrics"]
    assert code == 1, out
    assert metrics["qp_failures"] == 0
    # The metrics end with the goal, which the first damping tick aborts.
    assert metrics["no_state_ticks"] == 1
    assert "QP failures 0 (1 ticks damping without a trustworthy state)" in out
