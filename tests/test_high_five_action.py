"""HighFive as an action in MuJoCo: phases, progress, cancellation, rejection, sim-to-real."""

import itertools

import numpy as np
import pytest

from actions import BusyPolicy, GoalRejectedError, GoalStatus, HighFiveGoal, StandGoal
from actions.go2.high_five_behaviour import (
    INVALID_HOLD_SECONDS,
    INVALID_TARGET_HEIGHT,
    ROBOT_NOT_READY,
)
from actions.go2.robot_context import tilt_deg
from sim.control_loop import ControlLoop
from tests.sweeps import quick_first
from wbc.model.description import LEGS, UNITREE_SDK_JOINT_NAMES

PHASES = ["shifting", "unloading", "raising", "ready", "lowering", "reloading", "shifting_back",
          "complete"]


class Watch:
    """Per-tick record of what matters for safety, on the true state: height, tilt."""

    def __init__(self, loop: ControlLoop):
        self.min_height = np.inf
        self.max_tilt = 0.0
        loop.hooks.append(self)

    def __call__(self, loop, out):
        q, _ = loop.true_state()
        self.min_height = min(self.min_height, q[2])
        self.max_tilt = max(self.max_tilt, tilt_deg(q))


def four_feet_loaded(loop, fr_min_n=30.0):
    forces = loop.sim.foot_contact_forces()
    return (loop.controller.stance_legs == list(LEGS) and forces["FR"][2] >= fr_min_n
            and all(forces[leg][2] > 5.0 for leg in LEGS))


@pytest.fixture(scope="module")
def high_five_run():
    loop = ControlLoop.simulated()
    watch = Watch(loop)
    events = []
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.40, hold_seconds=2), timeout=30.0,
        feedback_callback=lambda fb: events.append((loop.robot.time_s, fb.feedback)))
    return loop, watch, events, result


def test_high_five_succeeds_with_phases_in_order(high_five_run):
    loop, watch, events, result = high_five_run
    assert result.status is GoalStatus.SUCCEEDED
    assert result.result.success is True
    assert "foot raised to 0.400 m" in result.result.message
    phases = [fb.phase for _, fb in events]
    assert [p for i, p in enumerate(phases) if i == 0 or phases[i - 1] != p] == PHASES
    assert watch.min_height > 0.3 and watch.max_tilt < 5.0
    assert four_feet_loaded(loop)


def test_progress_is_monotone_and_feedback_at_least_20_hz(high_five_run):
    _, _, events, _ = high_five_run
    progress = [fb.progress for _, fb in events]
    assert progress[0] == 0.0 and progress[-1] == 1.0
    assert all(b >= a for a, b in itertools.pairwise(progress))
    times = np.array([t for t, _ in events])
    assert np.max(np.diff(times)) <= 0.05 + 1e-9


def cancel_instants():
    """20 instants over the 6.8 s of a 1 s-hold high five, one draw per stratum (seed 7)."""
    rng = np.random.default_rng(7)
    edges = np.linspace(0.02, 6.75, 21)
    return [float(rng.uniform(a, b)) for a, b in itertools.pairwise(edges)]


# Every fifth stratum in the quick stage (0.23, 2.00, 3.49 and 5.25 s: in the shift, the raise,
# the hold and the lowering); the other 16 in the slow one.
@pytest.mark.parametrize("cancel_at", quick_first(
    cancel_instants(), lambda t: cancel_instants().index(t) % 5 == 0), ids=lambda t: f"{t:.2f}s")
def test_cancel_at_any_instant(cancel_at):
    loop = ControlLoop.simulated()
    watch = Watch(loop)
    events = []
    future = loop.client("high_five").send_goal_async(
        HighFiveGoal(target_height=0.40, hold_seconds=1), feedback_callback=events.append)
    loop.spin_once()
    handle = future.result()
    assert handle.accepted
    start = loop.robot.time_s
    while loop.robot.time_s < start + cancel_at:
        loop.spin_once()
    phase_at_cancel = events[-1].feedback.phase
    cancel_time = loop.robot.time_s
    handle.cancel_goal_async()
    loop.spin_once()
    assert handle.status is GoalStatus.CANCELING, phase_at_cancel
    result_future = handle.get_result_async()
    while not result_future.done() and loop.robot.time_s < cancel_time + 1.5:
        loop.spin_once()
    assert result_future.done(), f"no result 1.5 s after a cancel in phase {phase_at_cancel}"
    result = result_future.result()
    assert result.status is GoalStatus.CANCELED
    assert result.result.success is False and result.result.message.startswith("canceled")
    assert four_feet_loaded(loop), loop.sim.foot_contact_forces()
    assert watch.min_height > 0.3 and watch.max_tilt < 8.0


@pytest.mark.parametrize("goal,code,message", [
    (HighFiveGoal(target_height=0.7, hold_seconds=2), INVALID_TARGET_HEIGHT,
     ("target_height: expected a height of the front-right foot above the ground in "
      "[0.10, 0.50] m, received 0.7")),
    (HighFiveGoal(target_height=-0.1, hold_seconds=2), INVALID_TARGET_HEIGHT, "received -0.1"),
    (HighFiveGoal(target_height=float("nan"), hold_seconds=2), INVALID_TARGET_HEIGHT,
     "received nan"),
    (HighFiveGoal(target_height=float("inf"), hold_seconds=2), INVALID_TARGET_HEIGHT,
     "received inf"),
    (HighFiveGoal(target_height=0.4, hold_seconds=-1), INVALID_HOLD_SECONDS,
     "hold_seconds: expected a whole number of seconds in [0, 60], received -1"),
    (HighFiveGoal(target_height=0.4, hold_seconds=61), INVALID_HOLD_SECONDS, "received 61"),
])
def test_bad_goals_are_rejected_and_the_robot_keeps_standing(goal, code, message):
    loop = ControlLoop.simulated()
    with pytest.raises(GoalRejectedError) as info:
        loop.client("high_five").send_goal_and_wait(goal, timeout=1.0)
    assert info.value.rejection.code == code
    assert message in info.value.rejection.message
    loop.spin_for(0.5)
    assert loop.context.is_standing() and four_feet_loaded(loop)


def test_fallen_robot_is_not_able():
    loop = ControlLoop.simulated()
    loop.context.q = loop.context.q.copy()
    loop.context.q[3:7] = [np.sin(0.5), 0.0, 0.0, np.cos(0.5)]  # rolled 57 deg
    future = loop.client("high_five").send_goal_async(
        HighFiveGoal(target_height=0.4, hold_seconds=1))
    loop.runner.tick(loop.robot.time_s)
    handle = future.result()
    assert not handle.accepted and handle.rejection.code == ROBOT_NOT_READY
    assert "robot not able: base tilt 57 deg" in handle.rejection.message


def test_same_behaviour_on_a_plant_in_unitree_sdk_order():
    loop = ControlLoop.simulated(actuator_order=UNITREE_SDK_JOINT_NAMES)
    assert loop.sim.model.actuator(0).name == "FR_hip"
    assert loop.robot.robot.joint_names == UNITREE_SDK_JOINT_NAMES
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.35, hold_seconds=0), timeout=30.0)
    assert result.status is GoalStatus.SUCCEEDED, result.result.message
    assert four_feet_loaded(loop)


def test_high_five_stands_up_first_when_lying():
    loop = ControlLoop.simulated(pose="lying")
    events = []
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.30, hold_seconds=0), timeout=30.0,
        feedback_callback=lambda fb: events.append(fb.feedback.phase))
    assert result.status is GoalStatus.SUCCEEDED, result.result.message
    assert events[0] == "standing" and "raising" in events and events[-1] == "complete"


def test_preempting_goal_ends_the_high_five_with_who_preempted_it():
    loop = ControlLoop.simulated(busy_policy=BusyPolicy.PREEMPT)
    high_five = loop.client("high_five").send_goal_async(
        HighFiveGoal(target_height=0.4, hold_seconds=2))
    loop.spin_for(2.5)
    stand = loop.client("stand").send_goal_async(StandGoal(duration_s=1.0))
    loop.spin_once()
    stand_handle = stand.result()
    result = high_five.result().get_result_async()
    while not result.done():
        loop.spin_once()
    assert result.result().status is GoalStatus.ABORTED
    assert f"preempted by goal {stand_handle.goal_id} (stand)" in result.result().result.message
    outcome = stand_handle.get_result_async()
    while not outcome.done():
        loop.spin_once()
    assert outcome.result().status is GoalStatus.SUCCEEDED
    assert four_feet_loaded(loop)
