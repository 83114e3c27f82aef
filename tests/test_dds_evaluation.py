"""Judging a run across processes: the controller's tick log joined with the bridge's truth."""

import math

import numpy as np
import pytest

from actions.goal_status import GoalStatus
from sim.dds_evaluation import goal_runs
from wbc.core.errors import ConfigurationError
from wbc.model.description import LEGS

N = 200
YAW = 0.3  # the estimator's heading differs from the simulator's by this [rad]
OFFSET = np.array([0.5, -0.2, 0.0])  # and its origin by this [m]
FR = LEGS.index("FR")


def _yaw_quaternion(yaw: float) -> np.ndarray:
    return np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])  # x, y, z, w


def _logs(foot_error_m: float = 0.002):
    """A standing robot whose raised FR foot is ``foot_error_m`` above its target."""
    truth_ticks = np.arange(1, N + 1, dtype=np.uint32)
    q_true = np.zeros((N, 19))
    q_true[:, 2] = 0.3
    q_true[:, 3:7] = _yaw_quaternion(YAW)
    feet_est = np.array([[0.19, 0.14, 0.0], [0.19, -0.14, 0.0],
                         [-0.19, 0.14, 0.0], [-0.19, -0.14, 0.0]])
    c, s = math.cos(YAW), math.sin(YAW)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    feet_true = np.repeat((feet_est @ rotation.T + OFFSET)[None], N, axis=0)
    truth = {"tick": truth_ticks, "t_s": truth_ticks * 2e-3, "q": q_true, "v": np.zeros((N, 18)),
             "foot_position_m": feet_true, "foot_force_n": np.full((N, 4), 37.0)}
    truth["q"][:, :3] = OFFSET + np.array([0.0, 0.0, 0.3])

    rows = N - 20  # the controller answered every state but the first ten and last ten
    q_est = np.zeros((rows, 19), dtype=np.float32)
    q_est[:, 2] = 0.3
    q_est[:, 6] = 1.0
    swing = np.zeros((rows, 4), dtype=bool)
    swing[50:150, FR] = True
    targets = np.full((rows, 4, 3), np.nan, dtype=np.float32)
    raised = feet_est[FR] + np.array([0.0, 0.0, 0.1])
    targets[50:150, FR] = raised
    targets[50:100, FR, 2] = np.linspace(0.0, 0.1, 50)  # rising, then held
    # The truth's raised foot: the target carried into its frame, plus the error.
    for k in range(50, 150):
        feet_true[k + 10, FR] = rotation @ targets[k, FR] + OFFSET + [0.0, 0.0, foot_error_m]
    goal_status = np.zeros(rows, dtype=np.int8)
    goal_status[20:170] = int(GoalStatus.EXECUTING)
    goal_action = np.full(rows, -1, dtype=np.int8)
    goal_action[20:170] = 0
    ticks = {"state_tick": truth_ticks[10:N - 10].astype(np.int64), "fresh": np.ones(rows, bool),
             "t_s": np.arange(rows) * 2e-3, "q": q_est, "v": np.zeros((rows, 18), np.float32),
             "swing": swing, "foot_target": targets, "goal_status": goal_status,
             "goal_action": goal_action, "action_names": np.array(["high_five"]),
             "goal_status_names": np.array([GoalStatus(k).name for k in range(7)])}
    return ticks, truth


def test_the_raised_foot_is_measured_in_the_truths_frame():
    (run,) = goal_runs(*_logs(foot_error_m=0.002))
    assert run.action == "high_five" and run.last_logged_status == "EXECUTING"
    assert run.ticks == 150
    assert run.raised_foot_rms_mm == pytest.approx(2.0, abs=1e-3)
    assert run.raised_foot_max_mm == pytest.approx(2.0, abs=1e-3)
    assert run.holding_rms_mm == pytest.approx(2.0, abs=1e-3)
    assert run.stance_travel_max_mm == pytest.approx(0.0, abs=1e-9)
    assert run.max_tilt_deg == pytest.approx(0.0, abs=1e-6)
    assert run.on_four_feet
    assert run.estimate["height_max_mm"] == pytest.approx(0.0, abs=1e-3)
    assert abs(run.estimate["yaw_drift_deg"]) < 1e-6


def test_a_larger_error_and_a_foot_off_the_floor_show():
    ticks, truth = _logs(foot_error_m=0.010)
    truth["foot_force_n"][-30:, 0] = 0.0  # from before the goal ends
    (run,) = goal_runs(ticks, truth)
    assert run.raised_foot_rms_mm == pytest.approx(10.0, abs=1e-3)
    assert run.final_foot_forces_n[0] == 0.0 and not run.on_four_feet


def test_logs_of_different_runs_are_refused():
    ticks, truth = _logs()
    truth["tick"] = truth["tick"] + 10_000
    with pytest.raises(ConfigurationError, match="none of the controller's state ticks"):
        goal_runs(ticks, truth)


def test_an_unreadable_log_names_it(tmp_path):
    with pytest.raises(ConfigurationError, match=r"^ticks: cannot read .*missing\.npz"):
        goal_runs(tmp_path / "missing.npz", tmp_path / "truth.npz")
