"""Sensor faults in closed loop: the estimator reports what it distrusts and goes on with the
rest; without trustworthy state the loop falls back to damping and the goal aborts."""

from __future__ import annotations

import numpy as np
import pytest

from actions import GoalStatus, HighFiveGoal
from actions.go2.robot_context import tilt_deg
from benchmarks.robustness import (
    HOLD_START_S,
    PUSH_INTO_HOLD_S,
    PlantCase,
    run_high_five,
    standing_on_four_feet,
)
from sim.control_loop import ControlLoop
from sim.mujoco_robot import MujocoRobot
from sim.sensor_faults import FAULT_KINDS, FaultyRobot, SensorFault
from sim.simulator import Go2Simulator
from tests.sweeps import quick_first
from wbc.controller.control_output import ControlStatus
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.estimation.estimators import DEFAULT_ESTIMATOR
from wbc.robot_io.motor_command import MotorCommand

#: Faults start 0.2 s into the hold (times from the goal's start [s]).
IN_THE_HOLD_S = HOLD_START_S + PUSH_INTO_HOLD_S
PHASES = ["shifting", "unloading", "raising", "ready", "lowering", "reloading", "shifting_back",
          "complete"]


class FaultLog:
    """Per tick: the estimator's fault text (when not empty) and the command's status."""

    def __init__(self) -> None:
        self.faults: set[str] = set()
        self.statuses: list[ControlStatus] = []

    def __call__(self, loop: ControlLoop, out) -> None:
        if loop.estimator.estimate.faults:
            self.faults.add(loop.estimator.estimate.faults)
        self.statuses.append(out.status)


def faulty_high_five(*faults: SensorFault, estimator: str = DEFAULT_ESTIMATOR):
    log = FaultLog()
    episode = run_high_five(PlantCase(sensor_faults=faults, estimator=estimator), hold_s=1,
                            hooks=[log])
    return episode, log


#: What each estimator does without the IMU's quaternion.
WITHOUT_QUATERNION = {"kf": "orientation from the gyroscope",
                      "inekf": "not used after the start (the orientation is the filter's own)"}


#: The quick stage's faults worked around, one per estimator (the others: ``make test-slow``).
QUICK_WORKED_AROUND = {("kf", "quaternion_nan"), ("inekf", "foot_zero")}


@pytest.mark.parametrize(("estimator", "fault", "reported"), quick_first([
    *((name, SensorFault("quaternion_nan", IN_THE_HOLD_S, 0.5),
       f"IMU quaternion non-finite ([nan, nan, nan, nan]): {note}")
      for name, note in WITHOUT_QUATERNION.items()),
    *((name, SensorFault("quaternion_not_unit", IN_THE_HOLD_S, 0.5),
       f"IMU quaternion not unit (norm 1.2, tolerance 0.01): {note}")
      for name, note in WITHOUT_QUATERNION.items()),
    ("inekf", SensorFault("accel_nan", IN_THE_HOLD_S, 0.5),
     "accelerometer non-finite ([nan, nan, nan]): predicting without it"),
    ("inekf", SensorFault("foot_zero", 0.0, 30.0, "RL"),
     "RL foot-force sensor stuck at 0: contact from the schedule"),
    ("inekf", SensorFault("foot_full_scale", 0.0, 30.0, "RL"),
     "RL foot-force sensor at full scale (1000): contact from the schedule"),
], lambda case: (case[0], case[1].kind) in QUICK_WORKED_AROUND, unpack=True),
    ids=lambda value: value.kind if isinstance(value, SensorFault) else (
    value if value in WITHOUT_QUATERNION else ""))
def test_a_fault_the_estimator_works_around_leaves_the_high_five_intact(estimator, fault,
                                                                         reported):
    episode, log = faulty_high_five(fault, estimator=estimator)
    assert episode.status is GoalStatus.SUCCEEDED, episode.message
    assert [phase for _, phase in episode.phases] == PHASES
    assert log.faults == {reported}
    assert set(log.statuses) == {ControlStatus.OK}
    s = episode.summary
    assert s.raised_foot_rms_mm <= 5.0 and s.holding_rms_mm <= 3.0
    assert s.stance_sliding_max_mm <= 2.0 and episode.max_tilt_deg <= 3.0
    assert s.estimate_velocity_rms_m_s <= 0.02 and s.estimate_height_max_mm <= 3.0
    assert episode.standing


# The dropout in the quick stage; the stale sample and the gyroscope in the slow one.
@pytest.mark.parametrize(("kind", "words"), quick_first([
    ("dropout", "no sensor sample this period"),
    ("stale", "stale sample (tick"),
    ("gyro_nan", "gyroscope non-finite"),
], lambda case: case[0] == "dropout", unpack=True))
def test_20_ms_without_trustworthy_samples_aborts_the_goal_with_the_reason(kind, words):
    episode, log = faulty_high_five(SensorFault(kind, IN_THE_HOLD_S, 0.02))
    assert episode.status is GoalStatus.ABORTED
    assert episode.message.startswith(
        "the state stopped being trustworthy (state estimate: no trustworthy sensor sample for "
        "11 ms (limit 10 ms): " + words)
    # 10 ms on the estimate's prediction, then the fallback until samples return; then the
    # recovery stand (the raised foot put down first) within the run's time after the goal.
    assert log.statuses.count(ControlStatus.FALLBACK) == 10
    assert not episode.fell and episode.max_tilt_deg < 6.0
    episode.loop.spin_for(2.0)
    assert episode.loop.ready and standing_on_four_feet(episode.loop)
    assert tilt_deg(episode.loop.true_state()[0]) < 1.0
    again = episode.loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.3, hold_seconds=0), timeout=15.0)
    assert again.status is GoalStatus.SUCCEEDED, again.result.message


def test_faults_are_checked_and_named():
    assert set(FAULT_KINDS) >= {"dropout", "stale", "quaternion_nan", "foot_zero",
                                "foot_full_scale", "joint_nan"}
    with pytest.raises(UnknownNameError, match=r"^unknown sensor fault 'blackout'; valid sensor "
                                               r"faults: dropout, stale, "):
        SensorFault("blackout", 1.0, 0.1)
    with pytest.raises(UnknownNameError, match=r"^unknown leg 'XX'"):
        SensorFault("foot_zero", 1.0, 0.1, "XX")
    with pytest.raises(ConfigurationError, match=r"^duration_s: expected a value in \[0, 3600\]"):
        SensorFault("dropout", 1.0, -0.1)
    with pytest.raises(ConfigurationError, match=r"^name: a dropout fault names no foot"):
        SensorFault("dropout", 1.0, 0.1, "FR")
    assert SensorFault("joint_nan", 1.0, 0.1).name == "FR_thigh_joint"
    assert SensorFault("foot_full_scale", 2.0, 0.5, "RL").describe() == (
        "the RL foot-force sensor reads its full scale from 2 s for 500 ms")


def test_the_faulty_robot_corrupts_only_while_a_fault_lasts():
    robot = FaultyRobot(MujocoRobot(Go2Simulator(), sensors="exact"), [
        SensorFault("joint_nan", 0.002, 0.002, "FR_calf_joint"),
        SensorFault("stale", 0.005, 0.001), SensorFault("dropout", 0.007, 0.001)])
    command = MotorCommand.pure_torque(np.zeros(12))
    seen = []
    for _ in range(9):
        record = robot.read_sensors()
        seen.append(None if record is None else (record.tick, bool(np.isnan(record.q[5]))))
        robot.write_command(command)
    assert seen == [(1, False), (2, False), (3, True), (4, True), (5, False), (5, False),
                    (7, False), None, (9, False)]
