"""``go2-wbc high-five`` with the IMU quaternion broken from t = 0: the default estimator (the
invariant EKF) needs it only to start, and starts without it (roll and pitch from the
accelerometer, one line says so); the high five SUCCEEDS with the report written."""

from __future__ import annotations

import pytest

from sim.cli.exit_codes import EXIT_SUCCEEDED
from tests.sweeps import quick_first
from tests.test_startup_faults_cli import run_cli


# The non-finite quaternion in the quick stage, the one not of unit norm in the slow one.
@pytest.mark.parametrize("fault", quick_first(["quaternion_nan,0,1", "quaternion_not_unit,0,1"],
                                              lambda fault: fault.startswith("quaternion_nan")))
def test_the_default_estimator_starts_without_the_quaternion(tmp_path, capsys, fault):
    code, lines, report = run_cli(tmp_path, capsys, fault)
    assert code == EXIT_SUCCEEDED
    assert ("[  0.000 s] state estimator: started without the IMU quaternion: roll and pitch "
            "from the accelerometer, yaw 0") in lines
    assert not [line for line in lines if "not controlling" in line]
    assert report["result"]["status"] == "SUCCEEDED"
    assert [mode["mode"] for mode in report["loop_modes"]] == ["CONTROLLING"]
    metrics = report["metrics"]
    assert metrics["max_base_tilt_deg"] < 1.0 and metrics["raised_foot_rms_mm"] < 5.0
    assert metrics["estimate_roll_max_deg"] < 0.5 and metrics["estimate_pitch_max_deg"] < 0.5
