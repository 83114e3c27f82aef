"""Walk and cmd_vel in closed loop in MuJoCo (the realistic plant, the estimate, 1 kHz),
measured on the simulator's truth: a Walk goal by distance, a cancel, a high five refused
while walking and run after it, a streamed velocity that stops after its timeout."""

import math

import numpy as np
import pytest

from actions import GoalStatus, HighFiveGoal, WalkGoal
from sim.control_loop import ControlLoop
from wbc.model.description import LEGS

pytestmark = pytest.mark.slow


def four_feet_loaded(loop: ControlLoop, min_n: float = 5.0) -> bool:
    """Every foot in the controller's support and pressing the ground in the truth."""
    forces = loop.sim.foot_contact_forces()
    return (loop.controller.schedule.support_legs() == list(LEGS)
            and all(forces[leg][2] > min_n for leg in LEGS))


def spin_until(loop: ControlLoop, done, limit_s: float) -> float:
    """Tick until ``done()`` (at most ``limit_s`` of robot time); the robot time then."""
    end = loop.robot.time_s + limit_s
    while not done() and loop.robot.time_s < end:
        loop.spin_once()
    return loop.robot.time_s


@pytest.fixture(scope="module")
def run():
    loop = ControlLoop.simulated()
    facts: dict = {}
    # A: 1 m forward at 0.5 m/s.
    q0, _ = loop.true_state()
    phases: list = []
    result = loop.client("walk").send_goal_and_wait(
        WalkGoal(forward_mps=0.5, distance_m=1.0), timeout=20.0,
        feedback_callback=lambda fb: phases.append((loop.robot.time_s, fb.feedback.phase)))
    q1, _ = loop.true_state()
    stop_s = next(t for t, phase in phases if phase == "stopping")
    facts["distance"] = (result, float(np.hypot(*(q1[:2] - q0[:2]))), phases[-1][0] - stop_s,
                         four_feet_loaded(loop), math.degrees(2 * math.asin(q1[5])))
    # B: a high five while walking, then a cancel 1 s after the walk's acceptance.
    walk = loop.client("walk")
    future = walk.send_goal_async(WalkGoal(forward_mps=0.3, yaw_rate_radps=0.5, duration_s=10))
    spin_until(loop, future.done, 0.1)
    handle = future.result()
    refused = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.35))
    spin_until(loop, refused.done, 0.1)
    spin_until(loop, lambda: False, 1.0)
    cancel_s = loop.robot.time_s
    handle.cancel_goal_async()
    ended = handle.get_result_async()
    end_s = spin_until(loop, ended.done, 3.0)
    facts["cancel"] = (refused.result(), ended.result(), end_s - cancel_s, four_feet_loaded(loop))
    # C: cmd_vel at 10 Hz for 1.5 s, then nothing.
    stream = loop.context.velocity_stream
    x0 = loop.true_state()[0][0]
    for _ in range(15):
        loop.command_velocity(0.3, 0.0, 0.0)
        spin_until(loop, lambda: False, 0.1)
    last_s = loop.robot.time_s
    end_s = spin_until(loop, lambda: not stream.walking, 3.0)
    q, v = loop.true_state()
    facts["stream"] = (end_s - last_s, float(q[0] - x0), float(np.linalg.norm(v[:2])),
                       four_feet_loaded(loop), stream.timeout_s)
    # D: a high five after walking.
    facts["high_five"] = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.35, hold_seconds=1), timeout=20.0)
    print("measured:", {key: value if key != "high_five" else value.status.name
                        for key, value in facts.items()})
    return facts


def test_a_walk_by_distance_succeeds_and_stops_on_four_feet_within_a_second(run):
    result, travelled, stop_s, loaded, yaw_deg = run["distance"]
    assert result.status is GoalStatus.SUCCEEDED, result.result.message
    assert result.result.message.endswith("on four loaded feet")
    assert result.result.message.startswith("walk done: walked 1.00 m of 1 m, ")
    assert 1.0 <= result.result.distance_m < 1.2  # the estimate's path: 1 m, then the stop
    assert 0.8 < travelled < 1.25  # the truth's displacement
    assert abs(yaw_deg) < 5.0
    assert stop_s < 1.0 and loaded


def test_a_high_five_is_refused_while_walking_and_a_cancel_stops_within_a_second(run):
    refused, ended, stop_s, loaded = run["cancel"]
    assert not refused.accepted and refused.rejection.code == 33
    assert refused.rejection.message.startswith("robot walking (for a walk goal)")
    assert ended.status is GoalStatus.CANCELED, ended.result.message
    assert ended.result.message.endswith("on four loaded feet")
    assert stop_s < 1.0 and loaded


def test_cmd_vel_walks_and_stops_after_its_timeout(run):
    after_last_s, forward_m, speed, loaded, timeout_s = run["stream"]
    assert forward_m > 0.2  # 1.5 s at 0.3 m/s, less the start's first steps
    assert timeout_s <= after_last_s < timeout_s + 1.0
    assert speed < 0.1 and loaded  # the truth's residual sway once stopped


def test_a_high_five_after_walking_succeeds(run):
    result = run["high_five"]
    assert result.status is GoalStatus.SUCCEEDED, result.result.message
