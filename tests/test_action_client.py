"""Tests of the action client: blocking waits (spin hook or ticking thread), timeouts, stress."""

from __future__ import annotations

import random
import sys
import threading
from collections import Counter
from typing import Any, Self

import pytest

from actions.action_client import ActionClient, ActionTimeoutError, RunnerStalledError
from actions.action_runner import ActionRunner, BusyPolicy
from actions.action_server import ActionServer
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.errors import ActionUsageError
from actions.go2.go2_interfaces import HIGH_FIVE, STAND, HighFiveGoal, HighFiveResult, StandGoal
from actions.goal_status import TERMINAL_STATUSES, GoalStatus
from actions.responses import GoalResponse, Rejection, WrappedResult
from tests.scripted_behaviour import ScriptedBehaviour, scripted_factory
from wbc.core.errors import ConfigurationError, WbcError

S = GoalStatus
HF = HighFiveGoal(target_height=0.1, hold_seconds=1)


class Loop:
    """Stands in for the simulation loop: each spin_once advances time and ticks the runner."""

    def __init__(self, runner: ActionRunner, dt: float = 0.25) -> None:
        self.runner = runner
        self.dt = dt
        self.now_s = 0.0
        self.spins = 0

    def spin_once(self) -> None:
        self.spins += 1
        self.now_s = self.spins * self.dt
        self.runner.tick(self.now_s)


def make_client(**script: Any) -> tuple[ActionRunner, ActionClient]:
    runner = ActionRunner()
    goal_callback = script.pop("goal_callback", None)
    ActionServer(
        runner,
        HIGH_FIVE,
        "high_five",
        lambda: ScriptedBehaviour(**script),
        goal_callback=goal_callback,
    )
    return runner, ActionClient(runner, "high_five")


class Ticker:
    """A thread that ticks the runner every 10 ms of simulated time until stopped."""

    def __init__(self, runner: ActionRunner) -> None:
        self.runner = runner
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        k = 0
        while not self.stop.is_set():
            self.runner.tick(k * 0.01)
            k += 1

    def __enter__(self) -> Self:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(timeout=5.0)
        assert not self.thread.is_alive()


# --- same thread, through the spin hook ------------------------------------------------------


def test_send_goal_and_wait_drives_the_registered_spin_hook() -> None:
    runner, client = make_client(steps=3)
    loop = Loop(runner)
    runner.set_spinner(loop.spin_once)
    feedback: list[float] = []
    result = client.send_goal_and_wait(
        HF, feedback_callback=lambda message: feedback.append(message.feedback.progress)
    )
    assert result == WrappedResult(
        "1", S.SUCCEEDED, HighFiveResult(success=True, message="succeeded after 3 steps")
    )
    assert loop.spins == 3  # accepted, started and stepped on the first tick
    assert feedback == [1 / 3, 2 / 3, 1.0]


def test_spin_hook_timeout_is_in_simulated_seconds_and_does_not_cancel() -> None:
    runner, client = make_client(steps=None, unwind_steps=1)
    loop = Loop(runner, dt=0.25)
    runner.set_spinner(loop.spin_once)
    loop.spin_once()  # t = 0.25 s
    with pytest.raises(ActionTimeoutError) as info:
        client.send_goal_and_wait(HF, timeout=1.0)
    assert str(info.value) == (
        "goal 1 (high_five) did not finish within 1 s of simulated time; it is still "
        "EXECUTING and has NOT been cancelled: cancel it with client.cancel(err.goal_handle)"
    )
    assert isinstance(info.value, TimeoutError) and isinstance(info.value, WbcError)
    assert runner.now_s == 1.25 and loop.spins == 5
    handle = info.value.goal_handle
    assert handle is not None and handle.status == S.EXECUTING
    assert info.value.goal_handle_future.result(timeout=0) is handle
    cancel = client.cancel(handle)
    loop.spin_once()
    assert cancel.result(timeout=0).accepted
    assert handle.get_result_async().result(timeout=0).status == S.CANCELED


def test_spin_hook_that_does_not_tick_is_reported() -> None:
    runner, client = make_client()

    def lazy_spin() -> None:
        pass

    runner.set_spinner(lazy_spin)
    with pytest.raises(RunnerStalledError) as info:
        client.send_goal_and_wait(HF)
    assert str(info.value) == (
        f"the spin hook {lazy_spin!r} returned without ticking the runner; "
        "spin_once must advance the control loop, ticking its runner at the loop's time"
    )


def test_spin_hook_is_used_only_by_the_thread_that_registered_it() -> None:
    runner, _ = make_client()
    loop = Loop(runner)
    runner.set_spinner(loop.spin_once)
    seen: list[Any] = []
    thread = threading.Thread(target=lambda: seen.append(runner.spinner_for_current_thread()))
    thread.start()
    thread.join(timeout=5.0)
    assert seen == [None]
    assert runner.spinner_for_current_thread() == loop.spin_once
    runner.set_spinner(None)
    assert runner.spinner_for_current_thread() is None


def test_rejected_goal_raises_with_code_and_message() -> None:
    runner, client = make_client(
        goal_callback=lambda goal: Rejection(7, "hold_seconds must be >= 1")
    )
    runner.set_spinner(Loop(runner).spin_once)
    with pytest.raises(GoalRejectedError) as info:
        client.send_goal_and_wait(HighFiveGoal(target_height=0.1, hold_seconds=0))
    assert str(info.value) == "goal 1 (high_five) was rejected (code 7): hold_seconds must be >= 1"
    assert info.value.rejection == Rejection(7, "hold_seconds must be >= 1")


def test_waiting_inside_a_tick_callback_is_refused() -> None:
    runner, client = make_client(steps=1)
    errors: list[BaseException] = []

    def on_feedback(message: Any) -> None:
        try:
            client.send_goal_and_wait(HF)
        except ActionUsageError as err:
            errors.append(err)

    client.send_goal_async(HF, feedback_callback=on_feedback)
    runner.tick(0.0)
    assert [str(err) for err in errors] == [
        (
            "send_goal_and_wait was called from inside a tick callback, where it would wait "
            "forever for the next tick; use send_goal_async with a done callback"
        )
    ]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"timeout": -1}, "timeout must be None or a finite number of seconds > 0; received -1"),
        (
            {"stall_timeout_s": float("inf")},
            "stall_timeout_s must be a finite number > 0; received inf",
        ),
    ],
)
def test_invalid_wait_arguments(kwargs: dict[str, Any], message: str) -> None:
    _, client = make_client()
    with pytest.raises(ConfigurationError) as info:
        client.send_goal_and_wait(HF, **kwargs)
    assert str(info.value) == message


# --- goals filled field by field, the server's copy, waiting for the server ----------------


class GoalKeeper(ScriptedBehaviour):
    """A scripted behaviour that keeps the goal it was started with."""

    def start(self, goal: Any, now_s: float) -> None:
        super().start(goal, now_s)
        self.goal = goal


def test_a_goal_filled_field_by_field_is_checked_when_sent_with_the_keyword_message() -> None:
    runner, client = make_client()
    goal = HighFiveGoal()
    goal.target_height = "high"  # the mistake is not caught while filling
    with pytest.raises(ConfigurationError) as sent:
        client.send_goal_async(goal)
    with pytest.raises(ConfigurationError) as built:
        HighFiveGoal(target_height="high")
    assert str(sent.value) == str(built.value) == (
        "HighFiveGoal.target_height must be a real number; received 'high' (type str)"
    )
    runner.tick(0.0)
    assert runner.event_log == []  # nothing was queued
    goal.target_height = 1  # an int is a real number: normalised on the server's copy
    handle_future = client.send_goal_async(goal)
    runner.tick(0.1)
    assert handle_future.result(timeout=0).goal == HighFiveGoal(target_height=1.0)
    assert type(handle_future.result(timeout=0).goal.target_height) is float


def test_the_server_works_on_its_own_copy_of_the_goal() -> None:
    made: list[ScriptedBehaviour] = []
    seen: list[Any] = []
    runner = ActionRunner()

    def goal_callback(goal: Any) -> GoalResponse:
        seen.append(goal)
        return GoalResponse.ACCEPT

    def factory() -> GoalKeeper:
        made.append(GoalKeeper(steps=2))
        return made[-1]

    ActionServer(runner, HIGH_FIVE, "high_five", factory, goal_callback=goal_callback)
    client = ActionClient(runner, "high_five")
    goal = HighFiveGoal()
    goal.target_height, goal.hold_seconds = 0.3, 2
    future = client.send_goal_async(goal)
    goal.target_height, goal.hold_seconds = 0.5, 9  # after sending: changes nothing
    runner.tick(0.0)
    handle = future.result(timeout=0)
    handle.goal.hold_seconds = 30  # nor does changing the handle's copy
    goal.hold_seconds = 10
    runner.tick(0.1)
    expected = HighFiveGoal(target_height=0.3, hold_seconds=2)
    assert seen == [expected] and made[0].goal == expected and handle.goal == expected
    assert seen[0] is not goal and made[0].goal is not goal
    assert handle.get_result_async().result(timeout=0).status == S.SUCCEEDED


def test_wait_for_server_and_server_is_ready() -> None:
    runner, client = make_client()
    assert client.server_is_ready() is True
    assert client.wait_for_server() is True
    assert client.wait_for_server(timeout_sec=0.0) is True
    runner.shutdown(0.0)
    assert client.server_is_ready() is False
    assert client.wait_for_server(timeout_sec=5.0) is False  # at once: it never restarts
    with pytest.raises(ConfigurationError) as info:
        client.wait_for_server(timeout_sec=-1.0)
    assert str(info.value) == (
        "timeout_sec must be None or a finite number of seconds >= 0; received -1.0"
    )


def test_client_in_rclpy_order_checks_the_interface() -> None:
    runner, _ = make_client()
    client = ActionClient(runner, HIGH_FIVE, "high_five")
    assert (client.action_name, client.action_type) == ("high_five", HIGH_FIVE)
    with pytest.raises(ConfigurationError) as info:
        ActionClient(runner, STAND, "high_five")
    assert str(info.value) == (
        "action 'high_five' serves the HighFive interface; received action_type Stand"
    )
    with pytest.raises(ConfigurationError, match="ActionClient needs the action's name"):
        ActionClient(runner, HIGH_FIVE)  # type: ignore[call-arg]
    with pytest.raises(ConfigurationError, match="action_type must be an ActionType"):
        ActionClient(runner, "HighFive", "high_five")


def test_anything_holding_the_runner_stands_for_the_node() -> None:
    runner, _ = make_client()
    node = Loop(runner)  # like a ControlLoop, it holds the runner as .runner
    client = ActionClient(node, HIGH_FIVE, "high_five")
    runner.set_spinner(node.spin_once)
    assert client.send_goal_and_wait(HF).status == S.SUCCEEDED
    with pytest.raises(ConfigurationError) as info:
        ActionClient(None, "high_five")  # type: ignore[arg-type]
    assert str(info.value) == (
        "runner must be an ActionRunner or hold one as .runner (e.g. a ControlLoop); "
        "received None"
    )


# --- another thread ticks ----------------------------------------------------------------


def test_send_goal_and_wait_while_another_thread_ticks() -> None:
    runner, client = make_client(steps=20)
    feedback_threads: set[int] = set()
    with Ticker(runner) as ticker:
        result = client.send_goal_and_wait(
            HF,
            timeout=30.0,
            feedback_callback=lambda message: feedback_threads.add(threading.get_ident()),
        )
    assert result.status == S.SUCCEEDED
    assert result.result.message == "succeeded after 20 steps"
    assert feedback_threads == {ticker.thread.ident}  # callbacks run on the ticking thread


def test_wall_clock_timeout_leaves_the_goal_running_until_cancelled() -> None:
    runner, client = make_client(steps=None, unwind_steps=1)
    with Ticker(runner):
        with pytest.raises(ActionTimeoutError) as info:
            client.send_goal_and_wait(HF, timeout=0.05)
        handle = info.value.goal_handle
        assert handle is not None and handle.status == S.EXECUTING
        assert "within 0.05 s of wall-clock time; it is still EXECUTING" in str(info.value)
        assert client.cancel(handle).result(timeout=10.0).accepted
        assert handle.get_result_async().result(timeout=10.0).status == S.CANCELED


def test_nothing_ticking_is_detected_by_a_stall_timeout() -> None:
    runner, client = make_client(steps=1)
    with pytest.raises(RunnerStalledError) as info:
        client.send_goal_and_wait(HF, stall_timeout_s=0.05)
    assert str(info.value) == (
        "nothing is ticking the runner: no tick in 0.05 s (wall-clock) while waiting for the "
        "goal request to 'high_five', and this thread registered no spin hook. Tick "
        "the runner at the loop's time from a control loop thread, or register the loop's "
        "spin_once with runner.set_spinner(...) on this thread"
    )
    assert isinstance(info.value, ActionTimeoutError)
    # the request is still queued: a later tick processes it
    runner.tick(0.0)
    assert info.value.goal_handle_future.result(timeout=0).accepted


def test_result_stays_on_the_handle_however_many_goals_follow() -> None:
    runner, client = make_client(steps=1)
    loop = Loop(runner)
    runner.set_spinner(loop.spin_once)
    future = client.send_goal_async(HF)
    loop.spin_once()
    first: ClientGoalHandle = future.result(timeout=0)
    for _ in range(50):
        client.send_goal_and_wait(HF)
    assert first.get_result_async().result(timeout=0) == WrappedResult(
        "1", S.SUCCEEDED, HighFiveResult(True, "succeeded after 1 steps")
    )


# --- stress --------------------------------------------------------------------------------


GOALS_PER_WORKER = 250


@pytest.mark.parametrize("policy", [BusyPolicy.REJECT, BusyPolicy.PREEMPT])
def test_many_threads_sending_and_cancelling_while_one_ticks(policy: BusyPolicy) -> None:
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)  # switch threads often, so requests land between ticks
    try:
        _stress(policy)
    finally:
        sys.setswitchinterval(interval)


def _stress(policy: BusyPolicy) -> None:
    runner = ActionRunner(busy_policy=policy, event_log_maxlen=None)
    ActionServer(runner, HIGH_FIVE, "high_five", scripted_factory([], steps=5, unwind_steps=3))
    ActionServer(
        runner,
        STAND,
        "stand",
        scripted_factory(
            [],
            steps=50,
            unwind_steps=None,
            result_type=STAND.result_type,
            feedback_type=STAND.feedback_type,
        ),
        cancel_callback=lambda goal_id, goal: (
            GoalResponse.REJECT if int(goal_id) % 3 == 0 else GoalResponse.ACCEPT
        ),
        max_unwind_s=0.05,
    )
    clients = {name: ActionClient(runner, name) for name in ("high_five", "stand")}
    goals = {"high_five": HF, "stand": StandGoal(duration_s=1.0)}
    workers_left = [4]
    errors: list[BaseException] = []
    ticks: list[int] = []
    handles: list[ClientGoalHandle] = []
    cancels: list[Any] = []
    done_calls: Counter[str] = Counter()
    lock = threading.Lock()

    def on_done(future: Any) -> None:
        with lock:
            done_calls[future.result().goal_id] += 1

    def ticker() -> None:
        # at least 3000 ticks, and on until every worker has sent all its goals
        k = 0
        try:
            while k < 3000 or workers_left[0] > 0:
                runner.tick(k * 0.01)
                k += 1
        except BaseException as err:  # noqa: BLE001 - reported by the assert below
            errors.append(err)
        finally:
            ticks.append(k)

    def worker(seed: int) -> None:
        rng = random.Random(seed)
        mine: list[ClientGoalHandle] = []
        try:
            for _ in range(GOALS_PER_WORKER):
                name = rng.choice(("high_five", "stand"))
                handle = clients[name].send_goal_async(goals[name]).result(timeout=10.0)
                mine.append(handle)
                if handle.accepted:
                    handle.get_result_async().add_done_callback(on_done)
                    if rng.random() < 0.3:
                        cancels.append(handle.cancel_goal_async())
                if rng.random() < 0.2:
                    cancels.append(rng.choice(mine).cancel_goal_async())
        except BaseException as err:  # noqa: BLE001 - reported by the assert below
            errors.append(err)
        finally:
            with lock:
                handles.extend(mine)
                workers_left[0] -= 1

    threads = [threading.Thread(target=worker, args=(100 + i,), daemon=True) for i in range(4)]
    tick_thread = threading.Thread(target=ticker, daemon=True)
    for thread in [tick_thread, *threads]:
        thread.start()
    for thread in [*threads, tick_thread]:
        thread.join(timeout=20.0)
        assert not thread.is_alive(), "deadlock"
    runner.shutdown(1e6)
    assert errors == []
    assert ticks[0] >= 3000 and len(handles) == 4 * GOALS_PER_WORKER

    log = runner.event_log
    terminal = Counter(e.goal_id for e in log if e.event in ("succeeded", "canceled", "aborted"))
    events_of: dict[str, set[str]] = {}
    for event in log:
        events_of.setdefault(event.goal_id, set()).add(event.event)
    accepted = [h for h in handles if h.accepted]
    rejected = [h for h in handles if not h.accepted]
    assert accepted and len({h.goal_id for h in handles}) == len(handles)
    assert set(events_of) - {""} == {h.goal_id for h in handles}
    for handle in accepted:
        wrapped = handle.get_result_async().result(timeout=0)
        assert wrapped.status in TERMINAL_STATUSES and wrapped.status == handle.status
        assert terminal[handle.goal_id] == 1, handle
        assert done_calls[handle.goal_id] == 1, handle
    for handle in rejected:
        assert events_of[handle.goal_id] == {"rejected"}, handle
    assert all(cancel.done() for cancel in cancels)
    assert runner.active_goal_id is None and runner.queued_goal_ids == ()
