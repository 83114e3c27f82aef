"""The Walk action's every state transition and the velocity stream (cmd_vel), on the GO2's
runner with a scripted walking motion: simulated time, no simulator."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
import pytest

from actions.action_client import ActionClient
from actions.go2 import walk_behaviour
from actions.go2.go2_actions import make_go2_runner
from actions.go2.go2_interfaces import HighFiveGoal, SitGoal, StandGoal, WalkGoal
from actions.go2.robot_context import RobotContext
from actions.goal_status import GoalStatus
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.locomotion.walking import WalkPhase
from wbc.model.description import Go2Description

DT = 0.01  # [s] a tick here: the behaviour's logic does not depend on the rate


class ScriptedWalking:
    """The walking motion's contract, scripted: 0.2 s STARTING, WALKING at the commanded
    velocity (measured = commanded), STOPPING for ``stop_s`` after ``request_stop``, DONE."""

    made: ClassVar[list[ScriptedWalking]] = []
    stop_s = 0.4

    def __init__(self, controller: object) -> None:
        self.phase = None
        self.gait_phase = 0.0
        self.distance_m = 0.0
        self.commanded_velocity = np.zeros(3)
        self.measured_velocity = np.zeros(3)
        self.calls: list[tuple] = []
        self._last_s = math.nan
        self._start_s = math.nan
        self._stop_at_s = math.inf
        ScriptedWalking.made.append(self)

    def start(self, now_s: float) -> None:
        self.calls.append(("start", round(now_s, 6)))
        self.phase, self._start_s, self._last_s = WalkPhase.STARTING, now_s, now_s

    def set_velocity(self, forward_mps: float, lateral_mps: float, yaw_rate_radps: float) -> None:
        self.calls.append(("set_velocity", forward_mps, lateral_mps, yaw_rate_radps))
        self.commanded_velocity = np.array([forward_mps, lateral_mps, yaw_rate_radps])

    def request_stop(self, now_s: float) -> None:
        self.calls.append(("request_stop", round(now_s, 6)))
        self.commanded_velocity = np.zeros(3)
        self.phase, self._stop_at_s = WalkPhase.STOPPING, now_s + self.stop_s

    def advance(self, now_s: float) -> WalkPhase:
        dt, self._last_s = now_s - self._last_s, now_s
        if self.phase is WalkPhase.STARTING and now_s - self._start_s >= 0.2 - 1e-9:
            self.phase = WalkPhase.WALKING
        if self.phase is WalkPhase.WALKING:
            self.measured_velocity = self.commanded_velocity.copy()
            self.distance_m += math.hypot(*self.commanded_velocity[:2]) * dt
        if self.phase is WalkPhase.STOPPING and now_s >= self._stop_at_s - 1e-9:
            self.phase = WalkPhase.DONE
        self.gait_phase = ((now_s - self._start_s) / 0.5) % 1.0
        return self.phase


@pytest.fixture(scope="module")
def controller():
    return WholeBodyController()


@pytest.fixture
def robot(controller, monkeypatch):
    """A standing robot's context, the GO2's runner on it, the scripted walking in use."""
    monkeypatch.setattr(walk_behaviour, "default_walking", ScriptedWalking)
    ScriptedWalking.made = []
    standing = Go2Description.default().pose("standing")
    controller.reset(standing, np.zeros(18))
    context = RobotContext(controller)
    context.observe(0.0, standing, np.zeros(18))
    runner = make_go2_runner(context)
    return Robot(context, runner)


class Robot:
    def __init__(self, context: RobotContext, runner) -> None:
        self.context, self.runner, self.now = context, runner, 0.0

    def run(self, seconds: float) -> None:
        for _ in range(round(seconds / DT)):
            self.now = round(self.now + DT, 9)
            self.context.now_s = self.now
            self.runner.tick(self.now)

    def send(self, action: str, goal, feedback: list | None = None):
        future = ActionClient(self.runner, action).send_goal_async(
            goal, feedback_callback=None if feedback is None else feedback.append)
        self.run(DT)
        return future.result()

    def result(self, handle):
        future = handle.get_result_async()
        assert future.done(), f"goal still {handle.status.name}"
        return future.result()


def phases(feedback: list) -> list[str]:
    """The feedback's phases, each once, in order."""
    names = [each.feedback.phase for each in feedback]
    return [name for i, name in enumerate(names) if i == 0 or names[i - 1] != name]


def test_succeeds_by_duration_with_phases_feedback_and_distance(robot):
    feedback: list = []
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=2.0), feedback)
    assert handle.accepted and robot.context.walking == "a walk goal"
    robot.run(3.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.SUCCEEDED
    walking = ScriptedWalking.made[0]
    assert walking.calls[:2] == [("start", 0.01), ("set_velocity", 0.5, 0.0, 0.0)]
    assert walking.calls[2] == ("request_stop", 2.01)  # 2 s after the start
    assert wrapped.result.distance_m == pytest.approx(0.5 * 1.8, abs=1e-9)
    assert wrapped.result.message == (
        "walk done: walked 2.00 s, 0.90 m in all, on four loaded feet")
    assert phases(feedback) == ["starting", "walking", "stopping", "complete"]
    progress = [each.feedback.progress for each in feedback]
    assert progress == sorted(progress) and progress[-1] == 1.0
    last = feedback[-2].feedback  # the last one while stopping
    assert last.distance_m == pytest.approx(0.9) and 0.0 <= last.gait_phase < 1.0
    walking_fb = [each.feedback for each in feedback if each.feedback.phase == "walking"]
    assert walking_fb[-1].forward_mps == 0.5 and walking_fb[-1].lateral_mps == 0.0
    assert robot.context.walking == ""


def test_succeeds_by_distance(robot):
    handle = robot.send("walk", WalkGoal(forward_mps=0.3, lateral_mps=0.4, yaw_rate_radps=0.2,
                                         distance_m=1.0))
    robot.run(3.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.SUCCEEDED
    walking = ScriptedWalking.made[0]
    assert walking.calls[1] == ("set_velocity", 0.3, 0.4, 0.2)
    stop = walking.calls[2]
    assert stop[0] == "request_stop" and stop[1] == pytest.approx(0.21 + 1.0 / 0.5, abs=DT)
    assert 1.0 <= wrapped.result.distance_m < 1.0 + 0.5 * DT + 1e-9
    assert wrapped.result.message.startswith("walk done: walked 1.00 m of 1 m, ")


@pytest.mark.parametrize("goal, code, message", [
    (WalkGoal(forward_mps=1.5, duration_s=1.0), 30,
     "forward_mps: expected a velocity in [-1, 1] m/s, received 1.5"),
    (WalkGoal(lateral_mps=-0.6, duration_s=1.0), 30,
     "lateral_mps: expected a velocity in [-0.4, 0.4] m/s, received -0.6"),
    (WalkGoal(yaw_rate_radps=math.nan, duration_s=1.0), 30,
     "yaw_rate_radps: expected a velocity in [-1.2, 1.2] rad/s, received nan"),
    (WalkGoal(forward_mps=0.5, duration_s=-1.0), 31,
     "duration_s: expected a duration in [0, 300] s, received -1.0"),
    (WalkGoal(forward_mps=0.5, distance_m=math.inf), 32,
     "distance_m: expected a path length in [0, 100] m, received inf"),
    (WalkGoal(forward_mps=0.5), 31,
     ("duration_s, distance_m: expected exactly one of them above 0 (walk for a time or for a "
     "path length), received duration_s=0.0, distance_m=0.0")),
    (WalkGoal(forward_mps=0.5, duration_s=1.0, distance_m=1.0), 31,
     ("duration_s, distance_m: expected exactly one of them above 0 (walk for a time or for a "
     "path length), received duration_s=1.0, distance_m=1.0")),
    (WalkGoal(yaw_rate_radps=1.0, distance_m=2.0), 32,
     ("distance_m: 2 m at 0 m/s would take inf s; expected a forward and lateral speed of at "
     "least 0.02 m/s and at most 300 s of walking")),
])
def test_bad_goals_are_rejected_naming_field_value_and_range(robot, goal, code, message):
    handle = robot.send("walk", goal)
    assert not handle.accepted
    assert (handle.rejection.code, handle.rejection.message) == (code, message)
    assert ScriptedWalking.made == []


def test_a_robot_on_its_side_is_not_able(robot):
    q = Go2Description.default().pose("standing")
    q[3:7] = [math.sin(0.5), 0.0, 0.0, math.cos(0.5)]  # rolled 57 deg
    robot.context.observe(0.0, q, np.zeros(18))
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=1.0))
    assert handle.rejection.code == 12
    assert handle.rejection.message == (
        "robot not able: base tilt 57 deg, height 0.34 m; it must be upright (send a Stand goal "
        "once it is)")


def test_cancel_stops_on_four_feet_and_ends_canceled(robot):
    feedback: list = []
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=5.0), feedback)
    robot.run(1.0)
    handle.cancel_goal_async()
    robot.run(DT)
    assert handle.status is GoalStatus.CANCELING
    walking = ScriptedWalking.made[0]
    assert walking.calls[-1] == ("request_stop", 1.02)
    robot.run(1.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.CANCELED
    assert wrapped.result.distance_m == pytest.approx(0.5 * 0.81)  # walking from 0.21 s
    assert wrapped.result.message == (
        "canceled (canceled by client request): stopped after 0.41 m, on four loaded feet")
    assert phases(feedback)[-2:] == ["stopping", "canceled"]


def test_controller_fault_stops_and_aborts_with_the_reason(robot):
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=5.0))
    robot.run(1.0)
    robot.context.fault = "QP infeasible"
    robot.context.consecutive_fallbacks = 1
    robot.run(DT)
    assert ScriptedWalking.made[0].calls[-1][0] == "request_stop"
    robot.context.fault, robot.context.consecutive_fallbacks = "", 0
    robot.run(1.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.ABORTED
    assert wrapped.result.message == (
        "aborted: controller fault (QP infeasible); stopped after 0.41 m, on four loaded feet")


def test_a_lasting_fault_ends_the_goal_at_once(robot):
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=5.0))
    robot.run(0.5)
    robot.context.fault = "QP infeasible"
    robot.context.consecutive_fallbacks = walk_behaviour.FAULT_LIMIT_TICKS
    robot.run(DT)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.ABORTED
    assert wrapped.result.message.startswith("aborted: controller fault for 50 ticks (QP infea")
    assert robot.context.walking == ""


def test_balance_loss_stops_and_aborts_with_the_reason(robot):
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=5.0))
    robot.run(0.5)
    q = Go2Description.default().pose("standing")
    q[3:7] = [math.sin(math.radians(10.0)), 0.0, 0.0, math.cos(math.radians(10.0))]  # 20 deg
    robot.context.observe(robot.now, q, np.zeros(18))
    robot.run(1.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.ABORTED
    assert wrapped.result.message == (
        "aborted: balance was being lost (base tilt 20.0 deg above 12 deg); stopped after "
        "0.15 m, on four loaded feet")


def test_a_stop_that_never_ends_aborts(robot, monkeypatch):
    monkeypatch.setattr(ScriptedWalking, "stop_s", 10.0)
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=0.5))
    robot.run(3.0)
    wrapped = robot.result(handle)
    assert wrapped.status is GoalStatus.ABORTED
    assert wrapped.result.message == "aborted: not on four loaded feet 2 s after the stop"


def test_the_end_waits_for_the_base_to_come_to_rest(robot):
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=0.5))
    robot.run(0.9)  # the stop was asked at 0.51 and ended at 0.91
    v = np.zeros(18)
    v[:2] = [0.2, 0.1]  # the estimate still moving
    robot.context.observe(robot.now, robot.context.q, v)
    robot.run(0.4)
    assert handle.status is GoalStatus.EXECUTING  # 0.15 s passed, but not at rest
    robot.run(0.1)
    wrapped = robot.result(handle)  # 0.5 s after the motion's end: over, the speed said
    assert wrapped.status is GoalStatus.SUCCEEDED
    assert wrapped.result.message.endswith("on four loaded feet, base still at 0.22 m/s")


def test_stands_up_first_when_lying(robot):
    robot.context.observe(0.0, Go2Description.default().pose("lying"), np.zeros(18))
    feedback: list = []
    handle = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=1.0), feedback)
    robot.run(1.0)
    assert ScriptedWalking.made[0].calls == []  # still standing up
    robot.context.observe(robot.now, Go2Description.default().pose("standing"), np.zeros(18))
    robot.run(2.5)
    assert robot.result(handle).status is GoalStatus.SUCCEEDED
    assert phases(feedback) == ["standing", "starting", "walking", "stopping", "complete"]
    assert ScriptedWalking.made[0].calls[0] == ("start", 1.51)  # after the 1.5 s stand


@pytest.mark.parametrize("action, goal", [("high_five", HighFiveGoal(target_height=0.35)),
                                          ("sit", SitGoal()), ("stand", StandGoal())])
def test_other_goals_are_rejected_while_walking_and_run_after(robot, action, goal):
    walk = robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=0.5))
    refused = robot.send(action, goal)
    assert not refused.accepted
    assert (refused.rejection.code, refused.rejection.message) == (33, (
        "robot walking (for a walk goal): stop it first (cancel the walk goal, or send a zero "
        "velocity command); it stops on four feet within a second"))
    robot.run(1.5)
    assert robot.result(walk).status is GoalStatus.SUCCEEDED
    assert robot.send(action, goal).accepted


def test_a_second_walk_while_walking_gets_the_busy_policy(robot):
    robot.send("walk", WalkGoal(forward_mps=0.5, duration_s=0.5))
    second = robot.send("walk", WalkGoal(forward_mps=0.2, duration_s=0.5))
    assert second.rejection.code == 3 and second.rejection.message.startswith("robot busy")


# -- the velocity stream (cmd_vel) -----------------------------------------------------------


def test_stream_starts_a_walk_steers_it_and_stops_after_its_timeout(robot):
    stream = robot.context.velocity_stream
    stream.command(0.4, 0.0, 0.0)
    robot.run(DT)
    assert robot.context.walking == "the velocity stream (cmd_vel)"
    walking = ScriptedWalking.made[0]
    assert walking.calls == [("start", 0.01), ("set_velocity", 0.4, 0.0, 0.0)]
    for _ in range(10):  # 10 Hz for 1 s
        robot.run(0.1)
        stream.command(0.4, 0.1, -0.3)
    robot.run(0.5)
    assert walking.calls[2] == ("set_velocity", 0.4, 0.1, -0.3)
    assert walking.calls[-1][0] == "set_velocity"  # the newest command, seen at 1.02
    robot.run(DT)
    assert walking.calls[-1] == ("request_stop", 1.52)  # 0.5 s after the tick that saw it
    robot.run(0.55)
    assert not stream.walking and robot.context.walking == ""
    ended = [e for e in robot.runner.event_log if e.event == "succeeded"]
    assert len(ended) == 1 and ended[0].now_s == 2.07 and (  # 0.4 s stop, 0.15 s settling
        "walk done: stopped: no velocity command for 0.5 s (its timeout), " in ended[0].detail)
    assert len(ScriptedWalking.made) == 1


def test_stream_timeout_is_the_commands_own(robot):
    stream = robot.context.velocity_stream
    stream.command(0.4, 0.0, 0.0, timeout_s=0.2)
    robot.run(0.2)
    assert len(ScriptedWalking.made[0].calls) == 2
    robot.run(DT)
    assert ScriptedWalking.made[0].calls[-1] == ("request_stop", 0.21)


def test_a_zero_command_stops_and_a_newer_one_walks_again(robot):
    stream = robot.context.velocity_stream
    stream.command(0.4, 0.0, 0.0)
    robot.run(0.3)
    stream.command(0.0, 0.0, 0.0)
    robot.run(DT)
    first = ScriptedWalking.made[0]
    assert first.calls[-1] == ("request_stop", 0.31)
    stream.command(-0.2, 0.0, 0.0)  # while stopping: the next walk once this one ended
    robot.run(0.5)
    assert len(ScriptedWalking.made) == 1
    robot.run(0.1)
    second = ScriptedWalking.made[1]  # the first ended at 0.86: 0.4 s stop, 0.15 s settling
    assert second.calls[:2] == [("start", 0.87), ("set_velocity", -0.2, 0.0, 0.0)]


def test_a_zero_command_when_idle_starts_nothing(robot):
    robot.context.velocity_stream.command(0.0, 0.0, 0.0)
    robot.run(0.1)
    assert ScriptedWalking.made == [] and robot.runner.active_goal_id is None


def test_stream_is_refused_while_another_goal_runs_with_the_reason(robot):
    high_five = robot.send("high_five", HighFiveGoal(target_height=0.35, hold_seconds=1))
    assert high_five.accepted
    stream = robot.context.velocity_stream
    stream.command(0.4, 0.0, 0.0)
    robot.run(DT)
    assert ScriptedWalking.made == [] and not stream.walking and stream.refused == 1
    assert stream.refusal.startswith("robot busy: goal 1 (high_five) is EXECUTING")


@pytest.mark.parametrize("args, kwargs, message", [
    ((1.2, 0.0, 0.0), {}, ("velocity command: forward_mps: expected a velocity in [-1, 1] m/s, "
                          "received 1.2")),
    ((0.0, 0.0, "1"), {}, ("velocity command: yaw_rate_radps: expected a velocity in "
                          "[-1.2, 1.2] rad/s, received '1'")),
    ((0.1, 0.0, 0.0), {"timeout_s": 0.0}, ("timeout_s: expected a time in (0, 10] s, "
                                          "received 0.0")),
])
def test_bad_commands_raise_naming_field_value_and_range(robot, args, kwargs, message):
    with pytest.raises(ConfigurationError) as info:
        robot.context.velocity_stream.command(*args, **kwargs)
    assert str(info.value) == message


def test_commands_from_another_thread_start_one_walk_and_the_last_one_steers(robot):
    """The stream's thread safety: 2,000 commands from a thread while the runner ticks here;
    one walk is started, and once the thread is done the newest command is the one used."""
    import threading

    stream = robot.context.velocity_stream
    stream.command(0.1, 0.0, 0.0)
    values = [round(0.1 + 0.0002 * k, 4) for k in range(2000)]

    def sender() -> None:
        for value in values:
            stream.command(value, 0.0, 0.0, timeout_s=5.0)

    thread = threading.Thread(target=sender)
    thread.start()
    while thread.is_alive():
        robot.run(DT)
    thread.join()
    robot.run(2 * DT)
    assert len(ScriptedWalking.made) == 1 and stream.walking
    assert ScriptedWalking.made[0].calls[-1] == ("set_velocity", values[-1], 0.0, 0.0)
    assert stream.received == 2001 and stream.refused == 0
