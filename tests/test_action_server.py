"""Tests of the action runner and servers: acceptance, busy policies, cancel, unwind, shutdown."""

from __future__ import annotations

from collections import Counter
from concurrent.futures import Future
from typing import Any

import pytest

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy, Event
from actions.action_server import ActionServer
from actions.action_type import ActionType
from actions.behaviour import Behaviour, StepResult
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.errors import ActionUsageError
from actions.go2.go2_interfaces import (
    HIGH_FIVE,
    SIT,
    STAND,
    HighFiveFeedback,
    HighFiveGoal,
    HighFiveResult,
    SitGoal,
    StandGoal,
    StandResult,
)
from actions.goal_status import LEGAL_TRANSITIONS, GoalStatus
from actions.responses import (
    CancelResponse,
    CancelReturnCode,
    GoalResponse,
    Rejection,
    RejectionCode,
    WrappedResult,
)
from tests.scripted_behaviour import ScriptedBehaviour, scripted_factory
from wbc.core.errors import ConfigurationError, UnknownNameError

S = GoalStatus
HF = HighFiveGoal(target_height=0.1, hold_seconds=1)
STATUS_EVENTS = {status.name.lower(): status for status in GoalStatus}


class Robot:
    """A runner with scripted servers, a client per server and the behaviours they made."""

    def __init__(self, busy_policy: BusyPolicy = BusyPolicy.REJECT) -> None:
        self.runner = ActionRunner(busy_policy=busy_policy, event_log_maxlen=None)
        self.made: dict[str, list[ScriptedBehaviour]] = {}
        self.clients: dict[str, ActionClient] = {}

    def serve(
        self,
        name: str = "high_five",
        action_type: ActionType = HIGH_FIVE,
        *,
        goal_callback: Any = None,
        cancel_callback: Any = None,
        max_unwind_s: float = 5.0,
        **script: Any,
    ) -> ActionClient:
        made = self.made.setdefault(name, [])
        script.setdefault("result_type", action_type.result_type)
        script.setdefault("feedback_type", action_type.feedback_type)
        ActionServer(
            self.runner,
            action_type,
            name,
            scripted_factory(made, **script),
            goal_callback=goal_callback,
            cancel_callback=cancel_callback,
            max_unwind_s=max_unwind_s,
        )
        self.clients[name] = ActionClient(self.runner, name)
        return self.clients[name]

    def send(self, name: str = "high_five", goal: Any = HF, **kwargs: Any) -> Future[Any]:
        return self.clients[name].send_goal_async(goal, **kwargs)

    def start(self, name: str = "high_five", goal: Any = HF) -> ClientGoalHandle:
        """Send a goal, tick at t = 0 s and return its handle."""
        future = self.send(name, goal)
        self.runner.tick(0.0)
        return done(future)

    def events(self, goal_id: str | None = None) -> list[tuple[float, str, str]]:
        """(now_s, event, detail) of one goal, or (now_s, goal_id, event) of all."""
        log = self.runner.event_log
        if goal_id is None:
            return [(e.now_s, e.goal_id, e.event) for e in log]
        return [(e.now_s, e.event, e.detail) for e in log if e.goal_id == goal_id]


def done(future: Future[Any]) -> Any:
    """The result of a future that must already be resolved."""
    assert future.done(), "future not resolved yet"
    return future.result(timeout=0)


def transitions(log: list[Event]) -> set[tuple[GoalStatus, GoalStatus]]:
    """Every (old, new) status change recorded in an event log."""
    status: dict[str, GoalStatus] = {}
    seen = set()
    for event in log:
        new = STATUS_EVENTS.get(event.event)
        if new is not None:
            seen.add((status.get(event.goal_id, S.UNKNOWN), new))
            status[event.goal_id] = new
    return seen


# --- acceptance, start, feedback, result ------------------------------------------------------


def test_goal_is_accepted_started_and_stepped_on_the_tick_after_submission() -> None:
    robot = Robot()
    robot.serve(steps=3)
    future = robot.send()
    assert not future.done()
    robot.runner.tick(0.0)
    handle = done(future)
    assert (handle.goal_id, handle.accepted, handle.status) == ("1", True, S.EXECUTING)
    assert robot.made["high_five"][0].calls == [("start", 0.0, ""), ("step", 0.0, "")]
    robot.runner.tick(1.0)
    assert not handle.get_result_async().done()
    robot.runner.tick(2.0)
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.SUCCEEDED, HighFiveResult(success=True, message="succeeded after 3 steps")
    )
    assert [(t, e) for t, e, _ in robot.events("1")] == [
        (0.0, "accepted"),
        (0.0, "executing"),
        (0.0, "feedback"),
        (1.0, "feedback"),
        (2.0, "feedback"),
        (2.0, "succeeded"),
    ]
    assert robot.runner.active_goal_id is None


def test_feedback_arrives_in_order_after_the_state_change_and_before_the_result() -> None:
    robot = Robot()
    robot.serve(steps=3)
    seen: list[tuple[Any, ...]] = []
    handles: list[ClientGoalHandle] = []

    def on_feedback(message: Any) -> None:
        seen.append((message.goal_id, message.feedback, handles[0].status))

    future = robot.send(feedback_callback=on_feedback)
    future.add_done_callback(lambda f: handles.append(f.result()))
    robot.runner.tick(0.0)
    handles[0].get_result_async().add_done_callback(lambda f: seen.append(("done",)))
    robot.runner.tick(1.0)
    robot.runner.tick(2.0)
    assert seen == [
        ("1", HighFiveFeedback("running", 1 / 3), S.EXECUTING),
        ("1", HighFiveFeedback("running", 2 / 3), S.EXECUTING),
        ("1", HighFiveFeedback("complete", 1.0), S.EXECUTING),
        ("done",),
    ]


def test_goal_ids_are_sequential_strings_in_submission_order() -> None:
    robot = Robot()
    robot.serve(steps=1)
    futures = [robot.send() for _ in range(3)]
    robot.runner.tick(0.0)
    assert [done(f).goal_id for f in futures] == ["1", "2", "3"]
    assert [done(f).accepted for f in futures] == [True, False, False]


def test_wrong_goal_type_is_refused_at_send_time() -> None:
    robot = Robot()
    robot.serve()
    with pytest.raises(ConfigurationError) as info:
        robot.send(goal=StandGoal())
    assert str(info.value) == (
        "action 'high_five' takes a HighFiveGoal goal; received StandGoal(duration_s=2.0) "
        "(type StandGoal)"
    )


def test_unknown_action_name_lists_the_served_names() -> None:
    robot = Robot()
    robot.serve("high_five")
    robot.serve("stand", STAND)
    with pytest.raises(UnknownNameError) as info:
        ActionClient(robot.runner, "sitt")
    assert str(info.value) == (
        "no action server named 'sitt' on this runner; served names: high_five, stand"
    )


def test_server_validation() -> None:
    robot = Robot()
    robot.serve("high_five")
    with pytest.raises(ConfigurationError, match="'high_five' is already served on this runner"):
        robot.serve("high_five")
    with pytest.raises(ConfigurationError) as info:
        ActionServer(robot.runner, HIGH_FIVE, "x", ScriptedBehaviour, max_unwind_s=0.0)
    assert str(info.value) == ("max_unwind_s must be a finite number of seconds > 0; received 0.0")
    with pytest.raises(ConfigurationError, match="action_type must be an ActionType"):
        ActionServer(robot.runner, "HighFive", "y", ScriptedBehaviour)  # type: ignore[arg-type]


# --- goal callback -----------------------------------------------------------------------


def _raise(exception: Exception) -> Any:
    raise exception


@pytest.mark.parametrize(
    "goal_callback, factory_fails, expected",
    [
        (
            lambda goal: Rejection(-2, "target_height 0.9 m is out of range [0.05, 0.3] m"),
            False,
            Rejection(-2, "target_height 0.9 m is out of range [0.05, 0.3] m"),
        ),
        (
            lambda goal: GoalResponse.REJECT,
            False,
            Rejection(RejectionCode.REJECTED, "rejected by the goal callback of 'high_five'"),
        ),
        (
            lambda goal: _raise(ValueError("bad goal")),
            False,
            Rejection(
                RejectionCode.CALLBACK_ERROR,
                "goal callback of 'high_five' raised ValueError: bad goal",
            ),
        ),
        (
            lambda goal: None,
            False,
            Rejection(
                RejectionCode.CALLBACK_ERROR,
                "goal callback of 'high_five' returned None; expected GoalResponse.ACCEPT, "
                "GoalResponse.REJECT or a Rejection",
            ),
        ),
        (
            lambda goal: GoalResponse.ACCEPT,
            True,
            Rejection(
                RejectionCode.CALLBACK_ERROR,
                "behaviour factory of 'high_five' raised RuntimeError: no robot",
            ),
        ),
    ],
    ids=["rejection", "bare-reject", "raises", "returns-none", "factory-raises"],
)
def test_rejections_carry_a_code_and_a_message(
    goal_callback: Any, factory_fails: bool, expected: Rejection
) -> None:
    runner = ActionRunner()

    def factory() -> ScriptedBehaviour:
        if factory_fails:
            raise RuntimeError("no robot")
        return ScriptedBehaviour()

    ActionServer(runner, HIGH_FIVE, "high_five", factory, goal_callback=goal_callback)
    future = ActionClient(runner, "high_five").send_goal_async(
        HighFiveGoal(target_height=0.9, hold_seconds=1)
    )
    runner.tick(0.0)
    handle = done(future)
    assert (handle.accepted, handle.rejection, handle.status) == (False, expected, S.UNKNOWN)
    with pytest.raises(GoalRejectedError) as info:
        handle.get_result_async()
    assert str(info.value) == (
        f"goal 1 (high_five) was rejected (code {expected.code}): {expected.message}"
    )
    cancel = handle.cancel_goal_async()
    assert done(cancel) == CancelResponse(
        "1", CancelReturnCode.ERROR_UNKNOWN_GOAL_ID, "the goal was rejected; nothing to cancel"
    )
    assert [(e.event, e.detail) for e in runner.event_log] == [
        ("rejected", f"code {expected.code}: {expected.message}")
    ]
    assert runner.active_goal_id is None


def test_rejection_needs_an_int_code_and_a_message() -> None:
    with pytest.raises(ConfigurationError, match="Rejection.message must be a non-empty str"):
        Rejection(1, "")
    with pytest.raises(ConfigurationError, match="Rejection.code must be an int"):
        Rejection("busy", "robot busy")  # type: ignore[arg-type]


# --- cancel ------------------------------------------------------------------------------


def test_cancel_is_acknowledged_on_the_next_tick_then_unwinds() -> None:
    robot = Robot()
    robot.serve(steps=None, unwind_steps=3)
    handle = robot.start()
    status_at_reply: list[GoalStatus] = []
    cancel = handle.cancel_goal_async()
    cancel.add_done_callback(lambda f: status_at_reply.append(handle.status))
    assert not cancel.done() and handle.status == S.EXECUTING
    robot.runner.tick(1.0)
    assert done(cancel) == CancelResponse(
        "1", CancelReturnCode.ERROR_NONE, "goal 1 (high_five) is canceling"
    )
    assert done(cancel).accepted
    assert status_at_reply == [S.CANCELING]
    behaviour = robot.made["high_five"][0]
    assert behaviour.calls[-2:] == [
        ("cancel", 1.0, "canceled by client request"),
        ("step", 1.0, ""),
    ]
    robot.runner.tick(2.0)
    assert handle.status == S.CANCELING
    robot.runner.tick(3.0)
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.CANCELED, HighFiveResult(False, "canceled: canceled by client request")
    )


def test_unwind_that_overruns_max_unwind_s_is_aborted() -> None:
    robot = Robot()
    robot.serve(steps=None, unwind_steps=None, max_unwind_s=2.0)
    handle = robot.start()
    handle.cancel_goal_async()
    for now_s in (1.0, 2.0):
        robot.runner.tick(now_s)
        assert handle.status == S.CANCELING
    robot.runner.tick(3.0)
    message = (
        "unwind timed out: goal 1 (high_five) was still CANCELING 2 s after the cancel "
        "(canceled by client request); max_unwind_s is 2 s"
    )
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.ABORTED, HighFiveResult(False, message)
    )
    assert robot.made["high_five"][0].calls[-1] == ("abort_result", None, message)


@pytest.mark.parametrize(
    "cancel_callback, message",
    [
        (lambda goal_id, goal: Rejection(0, "cannot cancel mid-air"), "cannot cancel mid-air"),
        (
            lambda goal_id, goal: GoalResponse.REJECT,
            "rejected by the cancel callback of 'high_five'",
        ),
        (
            lambda goal_id, goal: _raise(KeyError("x")),
            "cancel callback of 'high_five' raised KeyError: 'x'",
        ),
    ],
)
def test_cancel_callback_can_refuse(cancel_callback: Any, message: str) -> None:
    robot = Robot()
    robot.serve(steps=3, cancel_callback=cancel_callback)
    handle = robot.start()
    cancel = handle.cancel_goal_async()
    robot.runner.tick(1.0)
    assert done(cancel) == CancelResponse("1", CancelReturnCode.ERROR_REJECTED, message)
    assert not done(cancel).accepted
    robot.runner.tick(2.0)
    assert done(handle.get_result_async()).status == S.SUCCEEDED
    assert (1.0, "cancel_refused", message) in robot.events("1")


def test_cancel_of_an_ended_goal_and_a_repeated_cancel() -> None:
    robot = Robot()
    robot.serve(steps=None, unwind_steps=2)
    handle = robot.start()
    first, second = handle.cancel_goal_async(), handle.cancel_goal_async()
    robot.runner.tick(1.0)
    assert done(first).message == "goal 1 (high_five) is canceling"
    assert done(second) == CancelResponse(
        "1", CancelReturnCode.ERROR_NONE, "goal 1 (high_five) is already canceling"
    )
    robot.runner.tick(2.0)
    late = handle.cancel_goal_async()
    robot.runner.tick(3.0)
    assert done(late) == CancelResponse(
        "1", CancelReturnCode.ERROR_GOAL_TERMINATED, "goal 1 (high_five) already ended CANCELED"
    )
    assert [c[0] for c in robot.made["high_five"][0].calls].count("cancel") == 1


# --- busy policies -----------------------------------------------------------------------


def test_reject_policy_rejects_a_second_goal_naming_the_running_one() -> None:
    robot = Robot(BusyPolicy.REJECT)
    robot.serve(steps=None)
    robot.serve("stand", STAND)
    first = robot.send()
    robot.runner.tick(0.0)
    second = robot.send("stand", StandGoal())
    robot.runner.tick(1.0)
    assert done(second).rejection == Rejection(
        RejectionCode.BUSY,
        "robot busy: goal 1 (high_five) is EXECUTING and the busy policy is REJECT; "
        "cancel that goal or wait for it to end, or use BusyPolicy.PREEMPT",
    )
    assert done(first).status == S.EXECUTING
    assert robot.made["stand"] == []


def test_preempt_policy_unwinds_the_running_goal_and_names_the_preempting_goal() -> None:
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=None, unwind_steps=2)
    robot.serve("stand", STAND, steps=1)
    old = robot.start()
    new = robot.send("stand", StandGoal())
    robot.runner.tick(1.0)
    assert done(new).status == S.ACCEPTED
    assert old.status == S.CANCELING
    assert robot.made["high_five"][0].calls[-2] == ("cancel", 1.0, "preempted by goal 2 (stand)")
    robot.runner.tick(2.0)  # the unwind ends: old is over, new still waits for the next tick
    assert done(old.get_result_async()) == WrappedResult(
        "1", S.ABORTED, HighFiveResult(False, "preempted by goal 2 (stand)")
    )
    assert done(new).status == S.ACCEPTED
    robot.runner.tick(3.0)
    assert done(done(new).get_result_async()).status == S.SUCCEEDED
    assert robot.events() == [
        (0.0, "1", "accepted"),
        (0.0, "1", "executing"),
        (0.0, "1", "feedback"),
        (1.0, "2", "accepted"),
        (1.0, "1", "canceling"),
        (1.0, "1", "feedback"),
        (2.0, "1", "aborted"),
        (3.0, "2", "executing"),
        (3.0, "2", "feedback"),
        (3.0, "2", "succeeded"),
    ]


def test_preempting_a_goal_that_has_not_started_aborts_it_and_it_never_runs() -> None:
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=None, unwind_steps=3)
    robot.serve("stand", STAND, steps=1)
    robot.serve("sit", SIT, steps=1)
    robot.send()
    robot.runner.tick(0.0)
    stand = robot.send("stand", StandGoal())
    robot.runner.tick(1.0)
    sit = robot.send("sit", SitGoal())
    robot.runner.tick(2.0)
    assert done(done(stand).get_result_async()) == WrappedResult(
        "2", S.ABORTED, StandResult(False, "preempted by goal 3 (sit) before it started")
    )
    assert robot.made["stand"][0].calls == [
        ("abort_result", None, "preempted by goal 3 (sit) before it started")
    ]
    for now_s in (3.0, 4.0):
        robot.runner.tick(now_s)
    assert done(done(sit).get_result_async()).status == S.SUCCEEDED
    assert [e for _, e, _ in robot.events("2")] == ["accepted", "aborted"]
    # the first goal was cancelled by goal 2's preemption and keeps that reason
    assert robot.events("1")[-1][1:] == (
        "aborted",
        repr(HighFiveResult(False, "preempted by goal 2 (stand)")),
    )


def test_a_goal_canceled_by_its_client_stays_canceled_when_preempted_meanwhile() -> None:
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=None, unwind_steps=2)
    robot.serve("stand", STAND, steps=1)
    old = robot.start()
    old.cancel_goal_async()
    robot.runner.tick(1.0)
    new = robot.send("stand", StandGoal())
    robot.runner.tick(2.0)
    assert done(old.get_result_async()).status == S.CANCELED
    robot.runner.tick(3.0)
    assert done(done(new).get_result_async()).status == S.SUCCEEDED


def test_cancel_of_a_goal_waiting_to_start_ends_it_without_running_it() -> None:
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=None, unwind_steps=3)
    robot.serve("stand", STAND)
    robot.send()
    robot.runner.tick(0.0)
    stand = robot.send("stand", StandGoal())
    robot.runner.tick(1.0)
    cancel = done(stand).cancel_goal_async()
    robot.runner.tick(2.0)
    assert done(cancel).accepted
    message = "canceled by client request before it started"
    assert done(done(stand).get_result_async()) == WrappedResult(
        "2", S.CANCELED, StandResult(False, message)
    )
    assert robot.made["stand"][0].calls == [("abort_result", None, message)]
    assert [e for _, e, _ in robot.events("2")] == ["accepted", "canceling", "canceled"]


# --- behaviour failures --------------------------------------------------------------------


@pytest.mark.parametrize("method", ["start", "step", "cancel"])
def test_behaviour_exception_aborts_the_goal_and_the_runner_goes_on(
    method: str, caplog: pytest.LogCaptureFixture
) -> None:
    robot = Robot()
    robot.serve("broken", steps=None, fail_in=method)
    robot.serve(steps=1)
    handle = robot.start("broken")
    if method == "cancel":
        handle.cancel_goal_async()
        robot.runner.tick(1.0)
    message = f"behaviour.{method} raised RuntimeError: {method} failed"
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.ABORTED, HighFiveResult(False, message)
    )
    assert f"behaviour.{method} of goal 1 (broken) raised" in caplog.text
    later = robot.send()
    robot.runner.tick(2.0)
    assert done(done(later).get_result_async()).status == S.SUCCEEDED


class Returns(Behaviour[Any, Any, Any]):
    """Steps return a preset value; cancel is recorded."""

    def __init__(self, value: Any, after_cancel: Any = None) -> None:
        self.value = value
        self.after_cancel = after_cancel
        self.canceled = False

    def start(self, goal: Any, now_s: float) -> None:
        pass

    def step(self, now_s: float) -> Any:
        return self.after_cancel if self.canceled else self.value

    def cancel(self, now_s: float, reason: str) -> None:
        self.canceled = True

    def abort_result(self, message: str) -> Any:
        return HighFiveResult(False, message)


OK = HighFiveResult(True, "ok")


@pytest.mark.parametrize(
    "behaviour, cancel, message",
    [
        (Returns(None), False, "behaviour.step returned None; expected a StepResult"),
        (
            Returns(StepResult.running(StandResult())),
            False,
            (
                "behaviour.step returned feedback StandResult(success=False, message=''); "
                "expected a HighFiveFeedback"
            ),
        ),
        (
            Returns(StepResult.succeeded(StandResult(True, "ok"))),
            False,
            (
                "behaviour.step returned result StandResult(success=True, message='ok'); "
                "expected a HighFiveResult"
            ),
        ),
        (
            Returns(StepResult.canceled(OK)),
            False,
            (
                "behaviour.step reported CANCELED while the goal was EXECUTING; "
                "a goal that is EXECUTING can only end SUCCEEDED or ABORTED"
            ),
        ),
        (
            Returns(StepResult.running(), StepResult.succeeded(OK)),
            True,
            (
                "behaviour.step reported SUCCEEDED while the goal was CANCELING; "
                "a goal that is CANCELING can only end CANCELED or ABORTED"
            ),
        ),
    ],
    ids=["not-a-step-result", "feedback-type", "result-type", "canceled-early", "late-success"],
)
def test_malformed_step_results_abort_the_goal_with_a_message(
    behaviour: Behaviour[Any, Any, Any], cancel: bool, message: str
) -> None:
    runner = ActionRunner()
    ActionServer(runner, HIGH_FIVE, "high_five", lambda: behaviour)
    handle_future = ActionClient(runner, "high_five").send_goal_async(HF)
    runner.tick(0.0)
    handle = done(handle_future)
    if cancel:
        handle.cancel_goal_async()
        runner.tick(1.0)
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.ABORTED, HighFiveResult(False, message)
    )


def test_step_result_validation() -> None:
    with pytest.raises(ConfigurationError) as info:
        StepResult(status=S.CANCELING, result=OK)
    assert str(info.value) == (
        "StepResult.status must be None or one of SUCCEEDED, CANCELED, ABORTED; "
        "received <GoalStatus.CANCELING: 3>"
    )
    with pytest.raises(ConfigurationError, match="needs a result exactly when"):
        StepResult(status=S.SUCCEEDED)


def test_abort_result_of_the_wrong_type_falls_back_to_the_action_failure_result(
    caplog: pytest.LogCaptureFixture,
) -> None:
    robot = Robot()
    # a Stand server whose behaviour speaks HighFive: its feedback and abort_result are wrong
    robot.serve("stand", STAND, result_type=HighFiveResult, feedback_type=HighFiveFeedback)
    future = robot.send("stand", StandGoal())
    robot.runner.tick(0.0)
    message = (
        "behaviour.step returned feedback HighFiveFeedback(phase='running', "
        "progress=0.3333333333333333); expected a StandFeedback"
    )
    assert done(done(future).get_result_async()) == WrappedResult(
        "1", S.ABORTED, StandResult(False, message)
    )
    assert "behaviour.abort_result of goal 1 (stand) failed" in caplog.text


# --- callbacks -----------------------------------------------------------------------------


def test_user_callback_exceptions_are_logged_and_never_break_the_tick(
    caplog: pytest.LogCaptureFixture,
) -> None:
    robot = Robot()
    robot.serve(steps=2)

    def bad_feedback(message: Any) -> None:
        raise ValueError("boom")

    future = robot.send(feedback_callback=bad_feedback)
    future.add_done_callback(lambda f: _raise(RuntimeError("handle callback")))
    robot.runner.tick(0.0)
    result_future = done(future).get_result_async()
    result_future.add_done_callback(lambda f: _raise(RuntimeError("result callback")))
    robot.runner.tick(1.0)
    assert done(result_future).status == S.SUCCEEDED
    assert [(t, e, d) for t, e, d in robot.events("1") if e == "callback_error"] == [
        (0.0, "callback_error", "feedback callback raised ValueError: boom"),
        (1.0, "callback_error", "feedback callback raised ValueError: boom"),
    ]
    assert "feedback callback of goal 1 (high_five) raised" in caplog.text
    assert "handle callback" in caplog.text and "result callback" in caplog.text


def test_ticking_from_inside_a_callback_is_refused_and_logged() -> None:
    robot = Robot()
    robot.serve(steps=1)
    future = robot.send(feedback_callback=lambda message: robot.runner.tick(5.0))
    robot.runner.tick(0.0)
    assert done(done(future).get_result_async()).status == S.SUCCEEDED
    errors = [d for _, e, d in robot.events("1") if e == "callback_error"]
    assert errors == [
        (
            "feedback callback raised ActionUsageError: ActionRunner.tick/shutdown called from "
            "inside a tick callback; call it from the control loop, after the current tick returns"
        )
    ]
    assert robot.runner.now_s == 0.0
    assert issubclass(ActionUsageError, RuntimeError)


def test_time_must_be_finite_and_must_not_go_backwards() -> None:
    runner = ActionRunner()
    runner.tick(1.0)
    with pytest.raises(ConfigurationError) as info:
        runner.tick(0.5)
    assert str(info.value) == "now_s must not go backwards: received 0.5 after 1.0"
    with pytest.raises(ConfigurationError, match="now_s must be a finite time"):
        runner.tick(float("nan"))
    runner.tick(1.0)  # equal time is allowed
    assert runner.tick_count == 2


# --- shutdown ------------------------------------------------------------------------------


def test_shutdown_ends_every_goal_exactly_once_and_rejects_new_goals() -> None:
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=None, unwind_steps=None, max_unwind_s=100.0)
    robot.serve("stand", STAND)
    first = robot.send()
    robot.runner.tick(0.0)
    queued = robot.send("stand", StandGoal())  # preempts: first unwinds, queued waits
    robot.runner.tick(1.0)
    # The running goal first (unwinding), then the one waiting.
    assert [(r.goal_id, r.status) for r in robot.runner.active_goals()] == [
        ("1", S.CANCELING), ("2", S.ACCEPTED)]
    pending = robot.send()  # never reaches a tick
    pending_cancel = done(queued).cancel_goal_async()
    finished: Counter[str] = Counter()
    for handle_future in (first, queued):
        done(handle_future).get_result_async().add_done_callback(
            lambda f: finished.update([f.result().goal_id])
        )
    robot.runner.shutdown(5.0)
    assert done(done(first).get_result_async()) == WrappedResult(
        "1",
        S.ABORTED,
        HighFiveResult(False, "runner shut down at t=5 s while the goal was CANCELING"),
    )
    assert done(done(queued).get_result_async()) == WrappedResult(
        "2", S.ABORTED, StandResult(False, "runner shut down at t=5 s before the goal started")
    )
    shut_down = Rejection(
        RejectionCode.SHUT_DOWN,
        "the action runner was shut down at t=5 s; it accepts no new goals",
    )
    assert done(pending).rejection == shut_down
    assert done(pending_cancel) == CancelResponse(
        "2", CancelReturnCode.ERROR_GOAL_TERMINATED, "goal 2 (stand) already ended ABORTED"
    )
    assert finished == {"1": 1, "2": 1}
    # afterwards: rejected at once (no tick needed), idempotent, ticks are harmless
    assert done(robot.send()).rejection == shut_down
    log_length = len(robot.runner.event_log)
    robot.runner.shutdown(6.0)
    robot.runner.tick(7.0)
    assert len(robot.runner.event_log) == log_length
    terminal = Counter(
        goal_id
        for _, goal_id, event in robot.events()
        if event in ("succeeded", "canceled", "aborted")
    )
    assert terminal == {"1": 1, "2": 1}
    assert robot.runner.is_shut_down and robot.runner.active_goal_id is None
    assert robot.runner.queued_goal_ids == () and robot.runner.active_goals() == ()
    assert done(done(first).cancel_goal_async()) == CancelResponse(
        "1", CancelReturnCode.ERROR_GOAL_TERMINATED, "the runner is shut down; nothing to cancel"
    )


def test_shutdown_lets_an_executing_behaviour_release_the_robot() -> None:
    robot = Robot()
    robot.serve(steps=None)
    future = robot.send()
    robot.runner.tick(0.0)
    robot.runner.shutdown(2.0)
    assert robot.made["high_five"][0].calls[-2:] == [
        ("cancel", 2.0, "runner shut down at t=2 s"),
        ("abort_result", None, "runner shut down at t=2 s while the goal was EXECUTING"),
    ]
    assert done(done(future).get_result_async()).status == S.ABORTED


def test_shutdown_when_the_behaviour_cancel_raises_still_ends_the_goal_once() -> None:
    robot = Robot()
    robot.serve(steps=None, fail_in="cancel")
    handle = robot.start()
    robot.runner.shutdown(1.0)
    assert done(handle.get_result_async()) == WrappedResult(
        "1", S.ABORTED, HighFiveResult(False, "behaviour.cancel raised RuntimeError: cancel failed")
    )
    assert [e for _, e, _ in robot.events("1")].count("aborted") == 1


# --- every legal transition, and replays -----------------------------------------------------


def scripted_run() -> ActionRunner:
    """A run that drives every legal status transition, single-threaded and scripted."""
    robot = Robot(BusyPolicy.PREEMPT)
    robot.serve(steps=2, unwind_steps=1)
    robot.serve("sit", SIT, steps=2, end_status=S.ABORTED)
    robot.serve("stand", STAND, steps=None, unwind_steps=None, max_unwind_s=3.0)
    tick = iter(float(t) for t in range(100))
    robot.send()  # 1: UNKNOWN->ACCEPTED->EXECUTING->SUCCEEDED
    robot.runner.tick(next(tick))
    robot.runner.tick(next(tick))
    robot.send("sit", SitGoal())  # 2: EXECUTING->ABORTED
    robot.runner.tick(next(tick))
    robot.runner.tick(next(tick))
    hf = robot.send()  # 3: EXECUTING->CANCELING->CANCELED
    robot.runner.tick(next(tick))
    done(hf).cancel_goal_async()
    robot.runner.tick(next(tick))
    stand = robot.send("stand", StandGoal())  # 4: unwind overruns: CANCELING->ABORTED
    robot.runner.tick(next(tick))
    robot.send()  # 5: preempts 4, waits ...
    robot.runner.tick(next(tick))
    sit = robot.send("sit", SitGoal())  # 6: ... 5 is preempted before start: ACCEPTED->ABORTED
    robot.runner.tick(next(tick))
    done(sit).cancel_goal_async()  # 6: ACCEPTED->CANCELING->CANCELED
    robot.runner.tick(next(tick))
    for _ in range(5):
        robot.runner.tick(next(tick))
    assert done(done(stand).get_result_async()).status == S.ABORTED
    robot.runner.shutdown(next(tick))
    return robot.runner


def test_a_run_drives_every_legal_transition() -> None:
    legal = {(old, new) for old, news in LEGAL_TRANSITIONS.items() for new in news}
    assert transitions(scripted_run().event_log) == legal


def test_two_identical_runs_give_identical_event_logs() -> None:
    first, second = scripted_run().event_log, scripted_run().event_log
    assert first == second
    assert len(first) == 30
    assert (
        Event(
            8.0,
            "5",
            "aborted",
            "HighFiveResult(success=False, message='preempted by goal 6 (sit) before it started')",
        )
        in first
    )
    assert first[-1] == Event(15.0, "", "shutdown", "runner shut down at t=15 s")
