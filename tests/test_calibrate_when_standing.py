"""``run --dds --calibrate``'s callback (:class:`actions.robot.foot_calibration.
CalibrateWhenStanding`) on the wall-clock loop, with a fake clock and a simulated GO2 whose
foot sensors read 30 + 0.25 counts per N (unknown to the controller): it waits for the robot to
stand under control, refuses goals while the centre of mass circles, hands the estimator what
it learnt, and is abandoned (target back, calibration kept) when the state stops."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from actions.go2.go2_interfaces import HighFiveGoal
from actions.robot.control_loop import ControlLoop
from actions.robot.foot_calibration import CALIBRATING, CalibrateWhenStanding
from sim.mujoco_robot import MujocoRobot
from sim.sensor_model import SensorModel
from sim.simulator import Go2Simulator
from tests.test_dds_controller import PERIOD_S, FakeClock, TestRobot, realtime, tick_until
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError

TRUE_OFFSET, TRUE_GAIN = 30.0, 0.25


def _loop(clock: FakeClock) -> tuple[ControlLoop, TestRobot]:
    sim = Go2Simulator(timestep_s=1e-3)
    sensors = SensorModel.preset("go2").with_params(foot_force_offset=TRUE_OFFSET,
                                                    foot_force_gain=TRUE_GAIN)
    plant = MujocoRobot(sim, control_period_s=PERIOD_S, sensors=sensors, sensor_seed=0)
    sim.reset("standing")
    plant.sensors.reset()
    robot = TestRobot(plant, clock)
    return ControlLoop(robot, WholeBodyController(solver={"control_period_s": PERIOD_S})), robot


def _calibrating() -> tuple[ControlLoop, TestRobot, Any, CalibrateWhenStanding, list[str]]:
    """A started wall-clock loop with a 2 s calibration waiting for the robot to stand."""
    clock = FakeClock()
    loop, robot = _loop(clock)
    rt = realtime(loop, clock)
    said: list[str] = []
    calibration = CalibrateWhenStanding(2.0, said.append)
    rt.callbacks.append(calibration)
    rt.start()
    return loop, robot, rt, calibration, said


@pytest.fixture(scope="module")
def calibrated():
    loop, _, rt, calibration, said = _calibrating()
    tick_until(rt, lambda: calibration.routine is not None, "the calibration to start", 50)
    during = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3))
    rt.tick()
    rejection = during.result().rejection.message
    tick_until(rt, lambda: calibration.finished, "the calibration to end", 1200)
    after = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3))
    rt.tick()
    return loop, calibration, said, rejection, after.result().accepted


def test_it_learns_the_feet_within_10_percent_and_the_estimator_uses_them(calibrated):
    loop, calibration, said, _, _ = calibrated
    report = calibration.report
    assert report is not None and report.learnt, report
    np.testing.assert_allclose(report.feet.gains, TRUE_GAIN, rtol=0.10)
    np.testing.assert_allclose(report.feet.offsets, TRUE_OFFSET, atol=3.0)
    assert loop.estimator.foot_calibration == report.feet
    assert said[0].startswith("calibrating the sensors while standing (2 s")
    assert said[1].startswith("calibration: foot force [counts] = offset + gain x N (learnt")


def test_goals_are_refused_while_it_runs_and_accepted_after(calibrated):
    loop, _, _, rejection, accepted = calibrated
    assert rejection == f"robot not able: {CALIBRATING}"
    assert accepted and loop.context.goal_refusal == ""


def test_lost_state_abandons_it_and_puts_the_target_back():
    loop, robot, rt, calibration, said = _calibrating()
    target = loop.controller.com_target.copy()
    before = loop.estimator.foot_calibration
    tick_until(rt, lambda: calibration.routine is not None, "the calibration to start", 50)
    for _ in range(100):  # 0.2 s of the circle
        rt.tick()
    assert np.linalg.norm(loop.controller.com_target[:2] - target[:2]) > 0.02
    robot.dropping = True
    tick_until(rt, lambda: calibration.finished, "the calibration to be abandoned", 200)
    assert calibration.report is None and "no trustworthy state" in calibration.abandoned
    assert said[-1].startswith(f"calibration abandoned ({calibration.abandoned}): the "
                               "estimator keeps foot force [counts]")
    assert loop.estimator.foot_calibration == before
    assert calibration.routine not in loop.hooks
    np.testing.assert_allclose(loop.controller.com_target, target, atol=1e-9)


def test_a_bad_duration_is_refused_naming_it():
    with pytest.raises(ConfigurationError, match="duration_s"):
        CalibrateWhenStanding(0.0, print)
