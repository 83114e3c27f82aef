"""Adding an action takes three things: its .action file (tests/data/Wave.action), its behaviour
(WaveBehaviour below, which loads the interface from the file as a ROS 2 node imports its
generated one) and one line that serves it (in serve_wave); a client then uses it end to end.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from actions import (
    ActionClient,
    ActionRunner,
    ActionServer,
    ActionType,
    Behaviour,
    FeedbackMessage,
    GoalRejectedError,
    GoalResponse,
    GoalStatus,
    Rejection,
    StepResult,
    UnknownFieldError,
    set_message_fields,
)
from wbc.core.errors import ConfigurationError

WAVE_FILE = Path(__file__).resolve().parent / "data" / "Wave.action"
#: The action type: its classes are built from the file, nothing else declares them.
WAVE = ActionType.from_file(WAVE_FILE, package="toy_interfaces")
#: The goal callback's rejection code for a goal with no wave.
NO_WAVE = 10


def validate_wave_goal(goal: Any) -> GoalResponse | Rejection:
    """Accept a goal with at least one wave and a positive period."""
    if goal.waves < 1:
        return Rejection(NO_WAVE, f"waves: expected at least 1, received {goal.waves}")
    return GoalResponse.ACCEPT


class WaveBehaviour(Behaviour[Any, Any, Any]):
    """Waves in simulated time, with no robot: raising for one period, a period per wave,
    lowering for one period. Feedback at every change of phase or of the waves done."""

    def start(self, goal: Any, now_s: float) -> None:
        self.goal, self.start_s, self.last = goal, now_s, None
        self.canceled = ""

    def step(self, now_s: float) -> StepResult[Any, Any]:
        period, waves = self.goal.period_s, self.goal.waves
        elapsed = now_s - self.start_s
        if self.canceled:
            return StepResult.canceled(WAVE.Result(message=f"stopped: {self.canceled}"))
        if elapsed < period:
            phase, done = "raising", 0
        elif elapsed < (1 + waves) * period:
            phase, done = "waving", int(elapsed / period) - 1
        elif elapsed < (2 + waves) * period:
            phase, done = "lowering", waves
        else:
            return StepResult.succeeded(
                WAVE.Result(success=True, message=f"waved {waves} times"),
                WAVE.Feedback(phase="complete", waves_done=waves))
        feedback = WAVE.Feedback(phase=phase, waves_done=done)
        if feedback == self.last:
            return StepResult.running()
        self.last = feedback
        return StepResult.running(feedback)

    def cancel(self, now_s: float, reason: str) -> None:
        self.canceled = reason

    def abort_result(self, message: str) -> Any:
        return WAVE.Result(message=message)


class Loop:
    """Stands in for a control loop: each spin_once advances 0.25 s and ticks the runner."""

    def __init__(self, runner: ActionRunner) -> None:
        self.runner, self.now_s = runner, 0.0
        runner.set_spinner(self.spin_once)

    def spin_once(self) -> None:
        self.now_s += 0.25
        self.runner.tick(self.now_s)


def serve_wave() -> tuple[Loop, ActionClient]:
    runner = ActionRunner()
    ActionServer(runner, WAVE, "wave", WaveBehaviour, goal_callback=validate_wave_goal)
    return Loop(runner), ActionClient(runner, WAVE, "wave")


def test_the_toy_action_is_served_and_run_end_to_end_with_its_feedback() -> None:
    loop, client = serve_wave()
    goal = WAVE.Goal()  # built empty, filled field by field, as in ROS 2
    goal.waves = 2
    feedback: list[FeedbackMessage] = []
    outcome = client.send_goal_and_wait(goal, feedback_callback=feedback.append)
    assert outcome.status is GoalStatus.SUCCEEDED
    assert outcome.result == WAVE.Result(success=True, message="waved 2 times")
    assert [(f.feedback.phase, f.feedback.waves_done) for f in feedback] == [
        ("raising", 0), ("waving", 0), ("waving", 1), ("lowering", 2), ("complete", 2)]
    assert repr(feedback[0].feedback) == "WaveFeedback(phase='raising', waves_done=0)"
    assert loop.now_s == 2.25  # 0.5 s raising, 2 x 0.5 s waving, 0.5 s lowering, then done
    assert client.action_type.type_name == "toy_interfaces/action/Wave"


def test_the_toy_action_rejects_cancels_and_checks_its_fields_as_a_shipped_one_does() -> None:
    loop, client = serve_wave()
    with pytest.raises(GoalRejectedError) as rejected:
        client.send_goal_and_wait(WAVE.Goal(waves=0))
    assert rejected.value.rejection == Rejection(NO_WAVE, "waves: expected at least 1, received 0")
    handle = client.send_goal_async(WAVE.Goal(waves=3, period_s=1.0))
    loop.spin_once()
    handle.result().cancel_goal_async()
    loop.spin_once()
    result = handle.result().get_result_async().result(timeout=0)
    assert (result.status, result.result.message) == (
        GoalStatus.CANCELED, "stopped: canceled by client request")
    with pytest.raises(ConfigurationError) as wrong:
        client.send_goal_async(set_message_fields(WAVE.Goal(), {"waves": "two"}))
    assert str(wrong.value) == "WaveGoal.waves must be an integer; received 'two' (type str)"
    with pytest.raises(UnknownFieldError) as unknown:
        WAVE.Goal().wave = 2
    assert str(unknown.value) == "WaveGoal has no field 'wave'; its fields: waves, period_s"
