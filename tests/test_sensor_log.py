"""A run's sensor log: written by --log, read back, replayed offline, played to a loop."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

from actions.robot.recorded_robot import RecordedRobot
from sim.cli import main
from sim.control_loop import ControlLoop
from wbc import WholeBodyController, make_estimator
from wbc.controller.control_output import ControlStatus
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.robot_io.sensor_log import SensorLog, log_row


@pytest.fixture(scope="module")
def logged(tmp_path_factory):
    """A 0 s-hold high five's --log, with a 20 ms dropout in the middle of the raise."""
    path = tmp_path_factory.mktemp("log") / "run.npz"
    with contextlib.redirect_stdout(io.StringIO()):
        code = main(["high-five", "--hold", "0", "--sensor-fault", "dropout,2.5,0.005",
                     "--log", str(path)])
    assert code == 0
    return path, np.load(path)


def test_the_log_holds_what_the_estimator_read(logged):
    path, arrays = logged
    log = SensorLog.load(path)
    n = len(arrays["t_s"])
    assert len(log) == n and log.arrays["joint_q"].shape == (n, 12)
    first = log.record(0)
    np.testing.assert_array_equal(first.q, arrays["q"][0, 7:])  # the joints the estimate used
    missing = np.flatnonzero(np.isnan(log.arrays["sensor_stamp_s"]))
    assert len(missing) == 5  # the dropout's five ticks
    assert log.record(int(missing[0])) is None
    ticks = log.arrays["sensor_tick"]
    assert np.all(np.diff(ticks[np.isfinite(ticks)]) >= 1)
    schedule = log.arrays["contact_schedule"]
    fr = 1
    full = WholeBodyController().config.contacts.max_normal_force_n
    assert schedule[:, fr].min() == 0.0 and schedule[0, fr] == full  # FR swung: its bound 0


def test_an_estimator_replayed_on_the_log_follows_the_run(logged):
    path, arrays = logged
    log = SensorLog.load(path)
    for name in ("inekf", "kf"):
        q, v = log.replay(make_estimator(name))
        assert q.shape == arrays["q"].shape and np.all(np.isfinite(q))
        # Started afresh at the log's first tick, against the truth the run logged.
        assert np.abs(q[:, 2] - arrays["q_true"][:, 2]).max() < 3e-3, name
        error = np.linalg.norm(v[:, :3] - arrays["v_true"][:, :3], axis=1)
        assert np.sqrt(np.mean(error**2)) < 0.02, name
    # A replay is the same run every time; it differs from the run's own estimate, which
    # started 0.3 s earlier, by that start (its height by 1.6 mm here).
    q, v = log.replay(make_estimator())
    again, _ = log.replay(make_estimator())
    np.testing.assert_array_equal(q, again)
    assert np.abs(q[:, 2] - arrays["q"][:, 2]).max() < 3e-3
    assert np.abs(v[:, :3] - arrays["v"][:, :3]).max() < 0.02


def test_a_loop_on_the_recorded_robot_runs_open_loop_and_ends_safely(logged):
    path, _ = logged
    robot = RecordedRobot(SensorLog.load(path))
    loop = ControlLoop(robot, WholeBodyController())
    statuses = []
    while not robot.finished:
        statuses.append(loop.spin_once().status)
    assert len(robot.commands) == len(robot.log) - 1  # the first record started the estimator
    assert statuses.count(ControlStatus.OK) >= len(statuses) - 5
    for _ in range(12):  # past the log's end: no samples, then the safe command
        statuses.append(loop.spin_once().status)
    assert statuses[-1] is ControlStatus.FALLBACK
    assert "no sensor sample this period" in loop.last_output.message
    assert robot.time_s == pytest.approx(robot.log.arrays["sensor_stamp_s"][-1] + 0.012)


def test_a_log_without_sensor_arrays_or_samples_is_refused(tmp_path):
    path = tmp_path / "truth.npz"
    np.savez(path, t_s=np.zeros(3))
    with pytest.raises(ConfigurationError, match=r"^sensor log: missing arrays \['sensor_"):
        SensorLog.load(path)
    with pytest.raises(ConfigurationError, match=r"^sensor log: cannot read"):
        SensorLog.load(tmp_path / "nothing.npz")
    empty = SensorLog.from_rows([log_row(None, np.zeros(4))])
    with pytest.raises(ConfigurationError, match=r"its first tick has no sample"):
        empty.replay(make_estimator())
    with pytest.raises(ConfigurationError, match=r"^log: no tick of it has a sample"):
        RecordedRobot(empty)
    with pytest.raises(ConfigurationError, match=r"^log: expected a SensorLog"):
        RecordedRobot(str(path))  # type: ignore[arg-type]


def test_a_loop_states_what_it_cannot_do(logged):
    path, _ = logged
    robot = RecordedRobot(SensorLog.load(path))
    with pytest.raises(ConfigurationError, match=r"^robot: RecordedRobot lacks read_state\(\) .*"
                                                 r"it reports sensors only, not its exact "
                                                 r"state .*: estimate it with state='estimate'"):
        ControlLoop(robot, WholeBodyController(), state="truth")
    with pytest.raises(ConfigurationError, match=r"^estimator: given with state='truth'"):
        ControlLoop.simulated(state="truth", estimator=make_estimator())
    with pytest.raises(UnknownNameError, match=r"^unknown state source 'exact'; valid state "
                                               r"sources: estimate, truth"):
        ControlLoop.simulated(state="exact")
