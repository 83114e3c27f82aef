"""The episode runner in closed loop: a high five on the estimated state, a cancel, a push, a
timeout, a rejection, standing without a goal; every bound measured on the simulator's truth."""

from __future__ import annotations

import numpy as np
import pytest

from actions.go2.go2_actions import GO2_ACTIONS
from sim.control_loop import ControlLoop
from sim.disturbances import DelayedRobot, Push
from sim.episode import Episode
from sim.episode_loop import build_loop
from sim.episode_result import NO_GOAL, REJECTED, EpisodeListener
from sim.episode_runner import EpisodeRunner
from wbc.model.description import LEGS

HighFiveGoal = GO2_ACTIONS["high_five"].Goal
StandGoal = GO2_ACTIONS["stand"].Goal
HIGH_FIVE_PHASES = ["shifting", "unloading", "raising", "ready", "lowering", "reloading",
                    "shifting_back", "complete"]


class Heard(EpisodeListener):
    """What the runner told, in order: ``(what, sim time [s], detail)``."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, float, object]] = []

    def goal_sending(self, runner, now_s):
        self.calls.append(("sending", now_s, runner.episode.action))

    def goal_response(self, handle, now_s):
        self.calls.append(("response", now_s, handle.accepted))

    def feedback(self, sample, message):
        self.calls.append(("feedback", sample.t_s, sample.phase))

    def event(self, event):
        self.calls.append((event.event, event.t_s, event.details))

    def cancel_reply(self, response, now_s):
        self.calls.append(("cancel_reply", now_s, response.accepted))

    def kinds(self) -> list[str]:
        """The calls' kinds, repeated feedback folded into one."""
        kinds = [call[0] for call in self.calls]
        return [k for i, k in enumerate(kinds) if i == 0 or k != "feedback" or kinds[i - 1] != k]


def on_four_feet(loop: ControlLoop) -> bool:
    """Four feet in the controller's stance and loaded in MuJoCo (over 5 N each)."""
    forces = loop.sim.foot_contact_forces()
    return (len(loop.controller.stance_legs) == len(LEGS)
            and all(forces[leg][2] > 5.0 for leg in LEGS))


@pytest.fixture(scope="module")
def high_five():
    heard = Heard()
    runner = EpisodeRunner(Episode(), listener=heard, metrics=True, record=True)
    return runner, runner.run(), heard


def test_the_default_high_five_on_the_estimate_succeeds_measured_on_the_truth(high_five):
    runner, result, _ = high_five
    assert result.status == "SUCCEEDED" and result.succeeded, result.message
    assert result.message == ("high five done: foot raised to 0.400 m, held 2 s, back on four "
                              "feet")
    assert runner.loop.estimator is not None  # the controller read the estimate
    m = result.metrics
    assert m.raised_foot_rms_mm <= 5.0 and m.raised_foot_max_mm <= 10.0
    assert m.holding_rms_mm <= 3.0 and m.stance_sliding_max_mm <= 2.0
    assert m.min_stance_normal_force_n >= 5.0 and m.min_com_margin_mm > 10.0
    assert m.max_base_tilt_deg < 3.0 and not m.fell and m.qp_failures == 0
    assert 0 < m.estimate_velocity_rms_m_s <= 0.02 and m.estimate_height_max_mm <= 3.0
    assert on_four_feet(runner.loop)


def test_the_result_tells_the_episode_in_order(high_five):
    runner, result, heard = high_five
    assert result.sent_s == pytest.approx(0.3)
    assert [phase for _, phase in result.phases()] == HIGH_FIVE_PHASES
    assert [e.event for e in result.events] == ["accepted", "result"]
    assert result.events[0].t_s == pytest.approx(0.3)
    assert result.ticks == round(result.sim_s / 1e-3) == result.metrics.ticks == 7804
    assert len(runner.recorder.arrays()["t_s"]) == result.ticks
    progress = [sample.progress for sample in result.feedback]
    assert progress == sorted(progress) and progress[-1] == 1.0
    assert heard.kinds() == ["sending", "response", "feedback"]
    assert heard.calls[0] == ("sending", pytest.approx(0.3), "high_five")
    assert heard.calls[1] == ("response", pytest.approx(0.3), True)
    assert 0.0 < result.overhead_s < result.wall_s


def test_a_cancel_at_its_time_ends_canceled_on_four_feet():
    heard = Heard()
    runner = EpisodeRunner(Episode(cancel_at_s=2.5), listener=heard)
    result = runner.run()
    assert result.status == "CANCELED" and not result.succeeded
    assert "the foot is down" in result.message
    cancel = [e for e in result.events if e.event == "cancel_requested"]
    assert [(e.t_s, e.details) for e in cancel] == [
        (pytest.approx(2.5), {"reason": "cancel_at_s 2.5"})]
    assert ("cancel_reply", pytest.approx(2.5), True) in heard.calls
    phases = [phase for _, phase in result.phases()]
    assert phases[:3] == HIGH_FIVE_PHASES[:3] and phases[-1] == "canceled"
    assert on_four_feet(runner.loop)


def test_a_push_is_applied_at_its_time_relative_to_the_heading():
    base_y: list[float] = []
    push = Push(at_s=0.35, force_n=60.0, duration_s=0.1, direction_deg=90.0,
                relative_to_heading=True)
    episode = Episode(action="stand", goal=StandGoal(duration_s=0.5), pushes=(push,))
    runner = EpisodeRunner(episode, hooks=[lambda loop, out: base_y.append(
        loop.true_state()[0][1])])
    result = runner.run()
    assert result.status == "SUCCEEDED", result.message
    (event,) = [e for e in result.events if e.event == "push"]
    assert event.t_s == pytest.approx(0.35) and event.push == push
    assert event.details["force_n"] == pytest.approx([0.0, 60.0, 0.0], abs=0.5)  # to the left
    assert max(base_y) - base_y[0] > 0.001  # it moved left


def test_a_goal_that_overruns_its_timeout_is_canceled():
    result = EpisodeRunner(Episode(timeout_s=1.0)).run()
    assert result.status == "CANCELED"
    (timeout,) = [e for e in result.events if e.event == "timeout"]
    assert timeout.t_s == pytest.approx(1.3) and timeout.details == {
        "reason": "no result after 1 s of sim time"}


def test_a_rejected_goal_has_the_servers_reason_and_no_metrics():
    runner = EpisodeRunner(Episode(goal=HighFiveGoal(target_height=0.9, hold_seconds=0)),
                           metrics=True)
    result = runner.run()
    assert result.status == REJECTED and result.wrapped is None and result.metrics is None
    assert result.message.startswith("target_height: expected a height of the front-right "
                                     "foot above the ground in [0.10, 0.50] m, received 0.9")
    assert result.events == [] and result.ticks == 1


def test_without_a_goal_the_robot_stands_its_after_s_ticked_by_the_callers_tick():
    ticks: list[float] = []
    runner = EpisodeRunner(Episode(action=None, after_s=0.2), metrics=True)

    def tick() -> None:
        ticks.append(runner.loop.robot.time_s)
        runner.loop.spin_once()

    result = runner.run(tick=tick)
    assert result.status == NO_GOAL and result.ticks == len(ticks) == 200
    assert ticks[0] == pytest.approx(0.3) and result.metrics.ticks == 200
    assert result.metrics.stance_sliding_max_mm < 0.5 and on_four_feet(runner.loop)


def test_the_loop_is_built_from_the_episode():
    loop = build_loop(Episode(state="truth", command_delay_s=0.002, start_pose="lying",
                              plant="ideal"))
    assert loop.estimator is None and loop.state_source == "truth"
    assert isinstance(loop.robot.robot, DelayedRobot) and loop.robot.robot.delay_ticks == 2
    assert loop.sim.time_s == 0.0 and loop.true_state()[0][2] < 0.2  # lying
    assert np.isclose(loop.sim.model.dof_damping[6:], 0.0).all()  # the ideal plant's joints
