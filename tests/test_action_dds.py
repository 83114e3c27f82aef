"""Actions over DDS on the loopback interface: a DdsActionBridge serving a runner, DdsActionClients
in this process and in a second one (killed mid-goal), and a closed-loop high five in MuJoCo."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from actions.action_runner import ActionRunner, BusyPolicy
from actions.action_server import ActionServer
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.dds.dds_action_bridge import DdsActionBridge
from actions.dds.dds_action_client import ActionServerUnavailableError, DdsActionClient
from actions.dds.goal_request_check import TransportRejectionCode
from actions.dds.payload_codec import decode_message, encode_message
from actions.errors import ActionUsageError
from actions.go2.go2_interfaces import HIGH_FIVE, STAND, HighFiveGoal, HighFiveResult
from actions.goal_status import GoalStatus
from actions.messages import Duration
from actions.responses import CancelReturnCode, GoalResponse, Rejection
from actions.ros_interfaces.control_msgs import FOLLOW_JOINT_TRAJECTORY
from actions.ros_interfaces.trajectory_msgs import JointTrajectoryPoint
from tests.scripted_behaviour import ScriptedBehaviour, scripted_factory
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.action_endpoints import ActionEndpoints, topic_names
from wbc.robot_io.dds.action_messages import SendGoalRequest, SendGoalResponse
from wbc.robot_io.dds.domain_config import join_domain

ROOT = Path(__file__).resolve().parents[1]
#: A private domain on loopback; each test has its own topic prefix on it.
DOMAIN = 187
S = GoalStatus
HF = HighFiveGoal(target_height=0.1, hold_seconds=1)
#: Longest wait for anything that should take milliseconds [s, wall-clock].
WAIT_S = 10.0
#: Client lease in the tests [s], and the slack allowed on top of it [s].
LEASE_S, LEASE_SLACK_S = 0.5, 0.7


def wait_until(condition: Callable[[], bool], timeout_s: float = WAIT_S, what: str = "") -> float:
    """Wait for ``condition`` (checked every millisecond); return the wall time it took [s]."""
    start = time.monotonic()
    tick = threading.Event()
    while not condition():
        if time.monotonic() - start > timeout_s:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what or condition}")
        tick.wait(0.001)
    return time.monotonic() - start


class ServerLoop:
    """The control loop's thread: tick the runner (10 ms of simulated time a tick), then poll
    the bridge, about every millisecond of wall time."""

    def __init__(self, runner: ActionRunner, bridge: DdsActionBridge) -> None:
        self.runner, self.bridge = runner, bridge
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.error: BaseException | None = None

    def _run(self) -> None:
        k = 0
        try:
            while not self.stop.is_set():
                k += 1
                self.runner.tick(k * 0.01)
                self.bridge.poll()
                self.stop.wait(0.001)  # the loop's period
        except Exception as err:  # noqa: BLE001 - reported by __exit__
            self.error = err

    def __enter__(self) -> ServerLoop:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(timeout=WAIT_S)
        assert not self.thread.is_alive()
        assert self.error is None, self.error


class Served:
    """A runner serving scripted high fives over DDS under a fresh prefix, and its clients."""

    def __init__(self, busy_policy: BusyPolicy = BusyPolicy.REJECT, **script: Any) -> None:
        self.prefix = f"rt/t{os.getpid()}/u{uuid.uuid4().hex[:8]}"
        self.runner = ActionRunner(busy_policy=busy_policy)
        self.made: list[ScriptedBehaviour] = []
        goal_callback = script.pop("goal_callback", None)
        ActionServer(self.runner, HIGH_FIVE, "high_five", scripted_factory(self.made, **script),
                     goal_callback=goal_callback)
        self.bridge = DdsActionBridge(self.runner, domain_id=DOMAIN, prefix=self.prefix,
                                      client_lease_s=1.0)
        self.clients: list[DdsActionClient] = []

    def client(self, name: str = "high_five", action_type: Any = HIGH_FIVE,
               **kwargs: Any) -> DdsActionClient:
        kwargs.setdefault("lease_s", LEASE_S)
        client = DdsActionClient(action_type, name, domain_id=DOMAIN, prefix=self.prefix,
                                 **kwargs)
        self.clients.append(client)
        return client

    def close(self) -> None:
        for client in self.clients:
            client.close()
        self.bridge.close()


@pytest.fixture
def served(request: pytest.FixtureRequest) -> Iterator[Served]:
    """A served runner with its loop running; parametrize it (indirect) with the script."""
    robot = Served(**getattr(request, "param", {}))
    try:
        with ServerLoop(robot.runner, robot.bridge):
            yield robot
    finally:
        robot.close()


def accepted_handle(client: DdsActionClient, goal: Any = HF, **kwargs: Any) -> ClientGoalHandle:
    assert client.wait_for_server(WAIT_S)
    handle = client.send_goal_async(goal, **kwargs).result(timeout=WAIT_S)
    assert handle.accepted, handle.rejection
    return handle


# --- in one process ---------------------------------------------------------------------------


@pytest.mark.parametrize("served", [{"steps": 3}], indirect=True)
def test_goal_succeeds_with_its_feedback_and_statuses(served: Served) -> None:
    client = served.client()
    feedback: list[tuple[str, float]] = []
    result = client.send_goal_and_wait(
        HF, timeout=WAIT_S,
        feedback_callback=lambda m: feedback.append((m.feedback.phase, m.feedback.progress)))
    assert result.status is S.SUCCEEDED
    assert result.result == HighFiveResult(success=True, message="succeeded after 3 steps")
    assert uuid.UUID(result.goal_id)
    assert feedback == [("running", 1 / 3), ("running", 2 / 3), ("complete", 1.0)]
    local = served.bridge.goal_handle(result.goal_id)
    assert local is not None and local.status is S.SUCCEEDED and local.goal == HF


def reject_low_goals(goal: HighFiveGoal) -> GoalResponse | Rejection:
    if goal.target_height < 0.2:
        return Rejection(10, f"target_height: expected [0.20, 0.45] m, received "
                             f"{goal.target_height!r}")
    return GoalResponse.ACCEPT


@pytest.mark.parametrize("served", [{"goal_callback": reject_low_goals}], indirect=True)
def test_rejection_carries_the_servers_code_and_reason(served: Served) -> None:
    client = served.client()
    assert client.wait_for_server(WAIT_S)
    with pytest.raises(GoalRejectedError) as info:
        client.send_goal_and_wait(HF, timeout=WAIT_S)
    assert info.value.rejection == Rejection(10, "target_height: expected [0.20, 0.45] m, "
                                                 "received 0.1")
    assert str(info.value) == (f"goal {info.value.goal_id} (high_five) was rejected (code 10): "
                               "target_height: expected [0.20, 0.45] m, received 0.1")
    handle = client.send_goal_async(HF).result(timeout=WAIT_S)
    assert not handle.accepted and handle.status is S.UNKNOWN
    cancel = client.cancel(handle).result(timeout=0)
    assert cancel.return_code is CancelReturnCode.ERROR_UNKNOWN_GOAL_ID
    assert served.made == []


@pytest.mark.parametrize("served", [{"steps": None, "unwind_steps": 2}], indirect=True)
def test_cancel_unwinds_then_ends_canceled(served: Served) -> None:
    client = served.client()
    phases: list[str] = []
    handle = accepted_handle(client, feedback_callback=lambda m: phases.append(m.feedback.phase))
    wait_until(lambda: handle.status is S.EXECUTING and bool(phases), what="EXECUTING and feedback")
    response = client.cancel(handle).result(timeout=WAIT_S)
    assert (response.goal_id, response.return_code, response.message) == (
        handle.goal_id, CancelReturnCode.ERROR_NONE,
        f"goal {handle.goal_id} (high_five) is canceling")
    result = handle.get_result_async().result(timeout=WAIT_S)
    assert (result.status, result.result.message) == (
        S.CANCELED, "canceled: canceled by client request")
    assert handle.status is S.CANCELED and "unwinding" in phases
    again = client.cancel(handle).result(timeout=WAIT_S)
    assert (again.return_code, again.message) == (
        CancelReturnCode.ERROR_GOAL_TERMINATED,
        f"goal {handle.goal_id} (high_five) already ended CANCELED")
    assert [call[0] for call in served.made[0].calls].count("cancel") == 1


@pytest.mark.parametrize("served", [{"steps": None}], indirect=True)
def test_a_busy_robot_names_the_running_goal_by_its_uuid(served: Served) -> None:
    client = served.client()
    first = accepted_handle(client)
    second = client.send_goal_async(HF).result(timeout=WAIT_S)
    rejection = second.rejection
    assert rejection is not None and rejection.code == 3
    assert rejection.message.startswith(
        f"robot busy: goal {first.goal_id} (high_five) is EXECUTING")


def test_an_action_nobody_serves_names_what_is_served(served: Served) -> None:
    assert served.client().wait_for_server(WAIT_S)  # the directory is up on the domain
    wave = served.client("wave")
    assert not wave.wait_for_server(0.2)
    with pytest.raises(ActionServerUnavailableError) as info:
        wave.send_goal_and_wait(HF, timeout=WAIT_S, server_timeout_s=0.3)
    assert str(info.value) == (
        f"no action server 'wave' (go2_interfaces/action/HighFive) matched within 0.3 s on DDS "
        f"domain {DOMAIN} (interface 'lo', topics {served.prefix}/wave/...); action servers "
        "seen on this domain: high_five (go2_interfaces/action/HighFive)")
    with pytest.raises(ActionServerUnavailableError, match="call wait_for_server"):
        wave.send_goal_async(HF)


def test_a_client_whose_lease_is_too_long_is_refused_and_told_why(served: Served) -> None:
    slow = served.client(lease_s=2.0)  # the server accepts leases up to 1 s
    assert not slow.wait_for_server(0.5)
    assert "refused this client's liveliness lease_s=2 s" in slow.unavailable_reason(0.5)


class RawClient:
    """Writes goal requests as any program could, and reads the responses."""

    def __init__(self, prefix: str) -> None:
        self.dds = join_domain("lo", domain_id=DOMAIN)
        self.ends = ActionEndpoints.for_client(self.dds, prefix, "high_five", lease_s=LEASE_S)
        wait_until(lambda: not self.ends.unmatched(), what="the server's endpoints")

    def send(self, goal: str, *, action_name: str = "high_five",
             action_type: str = "go2_interfaces/action/HighFive",
             goal_id: str | None = None) -> SendGoalResponse:
        goal_id = goal_id or str(uuid.uuid4())
        self.ends.writers["send_goal_request"].write(
            SendGoalRequest("raw", goal_id, action_name, action_type, goal))
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            self.ends.wait(0.05)
            for sample in self.ends.take("send_goal_response", 16):
                if sample.sample_info.valid_data and sample.goal_id == goal_id:
                    return sample
        raise AssertionError(f"no response to goal {goal_id}")

    def close(self) -> None:
        self.ends.close()
        self.dds.close()


@pytest.mark.parametrize(("payload", "kwargs", "code", "message"), [
    ('{"target_height": "high"}', {}, TransportRejectionCode.MALFORMED_GOAL,
     ("goal {id} for 'high_five': HighFiveGoal.target_height must be a real number; received "
      "'high' (type str)")),
    ('{"hold_seconds": 2.5}', {}, TransportRejectionCode.MALFORMED_GOAL,
     ("goal {id} for 'high_five': HighFiveGoal.hold_seconds must be an integer; received 2.5 "
      "(type float)")),
    ('{"height": 0.3}', {}, TransportRejectionCode.MALFORMED_GOAL,
     ("goal {id} for 'high_five': HighFiveGoal has no field 'height'; its fields: "
      "target_height, hold_seconds")),
    ("nope", {}, TransportRejectionCode.MALFORMED_GOAL,
     ("goal {id} for 'high_five': the payload is not JSON (Expecting value: line 1 column 1 "
      "(char 0)); received 'nope'")),
    ("{}", {"action_type": "go2_interfaces/action/Stand"},
     TransportRejectionCode.INTERFACE_MISMATCH,
     ("action 'high_five' serves go2_interfaces/action/HighFive; the client sent a "
      "go2_interfaces/action/Stand goal")),
    ("{}", {"action_name": "wave"}, TransportRejectionCode.UNKNOWN_ACTION,
     ("goal {id} is for action 'wave' but came on the topic of 'high_five' "
      "({prefix}/high_five/send_goal/request); served actions: high_five")),
    ("{}", {"goal_id": "7"}, TransportRejectionCode.DUPLICATE_GOAL_ID,
     "goal_id must be a fresh UUID in canonical form"),
])
def test_malformed_requests_are_rejected_naming_what_is_wrong(
        served: Served, payload: str, kwargs: dict[str, str], code: int, message: str) -> None:
    raw = RawClient(served.prefix)
    try:
        response = raw.send(payload, **kwargs)
    finally:
        raw.close()
    expected = message.format(id=response.goal_id, prefix=served.prefix)
    assert (response.accepted, response.rejection_code) == (False, code)
    assert response.message.startswith(expected), response.message
    assert served.made == []


def test_the_robot_io_shares_the_bridges_domain(served: Served) -> None:
    """The robot I/O's participant joins the bridge's domain in the same process; a request
    for that domain with another configuration is refused, naming both; the bridge keeps
    serving once the robot I/O leaves."""
    with join_domain("lo", domain_id=DOMAIN) as robot_io:
        assert robot_io.participant.domain_id == DOMAIN
        with pytest.raises(ConfigurationError, match=rf"^interface: domain {DOMAIN} is already "
                           r"configured in this process for interface 'lo' \(multicast false\), "
                           r"received a request for interface 'lo' \(multicast true\)"):
            join_domain("lo", domain_id=DOMAIN, multicast=True)
    handle = accepted_handle(served.client())
    assert handle.get_result_async().result(timeout=WAIT_S).status is S.SUCCEEDED


def test_a_stand_client_of_high_five_is_rejected(served: Served) -> None:
    stand = served.client("high_five", STAND)
    assert stand.wait_for_server(WAIT_S)
    with pytest.raises(GoalRejectedError) as info:
        stand.send_goal_and_wait(STAND.Goal(), timeout=WAIT_S)
    assert info.value.rejection.code == TransportRejectionCode.INTERFACE_MISMATCH


@pytest.mark.parametrize("served", [{"steps": None, "unwind_steps": 1}], indirect=True)
def test_a_client_that_closes_mid_goal_has_its_goal_canceled(served: Served) -> None:
    client = served.client()
    handle = accepted_handle(client)
    local = served.bridge.goal_handle(handle.goal_id)
    assert local is not None
    client.close()
    with pytest.raises(ActionUsageError, match="was closed while goal"):
        handle.get_result_async().result(timeout=0)
    wait_until(lambda: local.status is S.CANCELED, what="the server to cancel the goal")
    cancels = [call for call in served.made[0].calls if call[0] == "cancel"]
    assert [reason for _, _, reason in cancels] == ["canceled by client request"]


def test_a_server_that_closes_mid_goal_fails_the_clients_futures() -> None:
    robot = Served(steps=None)
    try:
        client = robot.client()
        with ServerLoop(robot.runner, robot.bridge):
            handle = accepted_handle(client)
            robot.bridge.close()
            with pytest.raises(ActionServerUnavailableError, match="was lost"):
                handle.get_result_async().result(timeout=WAIT_S)
    finally:
        robot.close()


def test_any_action_travels_as_json_of_its_fields() -> None:
    goal = FOLLOW_JOINT_TRAJECTORY.Goal()
    goal.trajectory.joint_names = ["FR_calf_joint"]
    goal.trajectory.points = [JointTrajectoryPoint(positions=[-1.9 + 1e-12],
                                                   time_from_start=Duration(sec=1, nanosec=5))]
    goal.goal_time_tolerance = 0.25
    text = encode_message(goal, FOLLOW_JOINT_TRAJECTORY.Goal, what="goal")
    assert decode_message(text, FOLLOW_JOINT_TRAJECTORY.Goal, what="goal") == (
        goal.validated_copy())
    with pytest.raises(ConfigurationError) as info:
        encode_message(HF, FOLLOW_JOINT_TRAJECTORY.Goal, what="the goal of 'follow'")
    assert str(info.value).startswith(
        "the goal of 'follow' must be a FollowJointTrajectoryGoal; received HighFiveGoal(")


def test_arguments_are_checked() -> None:
    with pytest.raises(ConfigurationError, match=r"^domain_id: expected 0\.\.232"):
        DdsActionClient(HIGH_FIVE, "high_five", domain_id=233)
    with pytest.raises(ConfigurationError, match=r"^interface: expected one of this host's "
                       r"network interfaces \[.*'lo'.*\], received 'nope0'$"):
        DdsActionBridge(ActionRunner(), domain_id=DOMAIN, interface="nope0")
    with pytest.raises(ConfigurationError, match=r"lease_s must be a liveliness lease .* 0\.01"):
        DdsActionClient(HIGH_FIVE, "high_five", domain_id=DOMAIN, lease_s=0.01)
    with pytest.raises(ConfigurationError, match="action_name must be '/'-separated"):
        topic_names("rt/wbc/action", "high five")


# --- a second process -------------------------------------------------------------------------

CLIENT_SCRIPT = """
import sys
import threading
from actions.dds.dds_action_client import DdsActionClient
from actions.go2.go2_interfaces import HIGH_FIVE, HighFiveGoal
domain, prefix, height, hold = int(sys.argv[1]), sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
client = DdsActionClient(HIGH_FIVE, "high_five", domain_id=domain, prefix=prefix, lease_s=0.5)
printing = threading.Lock()  # feedback prints on the client's thread: one line at a time
def say(line):
    with printing:
        print(line, flush=True)
if not client.wait_for_server(30):
    say("no server")
    sys.exit(2)
phases = []
def feedback(message):
    if not phases or phases[-1] != message.feedback.phase:
        phases.append(message.feedback.phase)
        say(f"phase {message.feedback.phase}")
handle = client.send_goal_async(HighFiveGoal(target_height=height, hold_seconds=hold),
                                feedback).result(timeout=30)
say(f"{'accepted' if handle.accepted else 'rejected'} {handle.goal_id}")
sys.stdin.read()  # until killed
"""


class ClientProcess:
    """The client script in a second process; its stdout lines on a queue."""

    def __init__(self, prefix: str, height: float = 0.1, hold: int = 1) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-c", CLIENT_SCRIPT, str(DOMAIN), prefix, str(height), str(hold)],
            cwd=ROOT, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(line.strip())

    def wait_for_line(self, prefix: str, timeout_s: float = 60.0) -> str:
        deadline = time.monotonic() + timeout_s
        seen = []
        while (left := deadline - time.monotonic()) > 0:
            try:
                line = self.lines.get(timeout=left)
            except queue.Empty:
                break
            if line.startswith(prefix):
                return line
            seen.append(line)
        raise AssertionError(f"the client process printed no {prefix!r} in {timeout_s} s "
                             f"(exit code {self.process.poll()}); it printed {seen}")

    def kill(self) -> float:
        """SIGKILL it (no goodbye on the wire); the monotonic time of the kill."""
        self.process.send_signal(signal.SIGKILL)
        return time.monotonic()

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=WAIT_S)


@pytest.mark.parametrize("served", [{"steps": None, "unwind_steps": 1}], indirect=True)
def test_a_killed_client_process_has_its_goal_canceled_within_its_lease(served: Served) -> None:
    client = ClientProcess(served.prefix)
    try:
        goal_id = client.wait_for_line("accepted").split()[1]
        local = served.bridge.goal_handle(goal_id)
        assert local is not None
        wait_until(lambda: local.status is S.EXECUTING)
        killed_at = client.kill()
        wait_until(lambda: local.status is S.CANCELED, what="the server to cancel the goal")
        elapsed = time.monotonic() - killed_at
    finally:
        client.stop()
    assert elapsed < LEASE_S + LEASE_SLACK_S
    cancels = [call for call in served.made[0].calls if call[0] == "cancel"]
    assert [reason for _, _, reason in cancels] == ["canceled by client request"]


# --- closed loop in MuJoCo --------------------------------------------------------------------


@pytest.fixture
def simulated() -> Iterator[tuple[Any, DdsActionBridge, str]]:
    """A simulated GO2 whose loop runs free on a thread, its bridge polled by a tick hook."""
    from sim.control_loop import ControlLoop

    loop = ControlLoop.simulated()
    prefix = f"rt/t{os.getpid()}/u{uuid.uuid4().hex[:8]}"
    bridge = DdsActionBridge(loop, domain_id=DOMAIN, prefix=prefix)
    loop.hooks.append(bridge.tick_hook)
    stop = threading.Event()

    def run() -> None:
        while not stop.is_set():
            loop.spin_once()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield loop, bridge, prefix
    finally:
        stop.set()
        thread.join(timeout=WAIT_S)
        bridge.close()
    assert not thread.is_alive()


def test_high_five_from_a_dds_client_succeeds_in_closed_loop(simulated: Any) -> None:
    loop, _, prefix = simulated
    phases: list[str] = []

    def feedback(message: Any) -> None:
        if not phases or phases[-1] != message.feedback.phase:
            phases.append(message.feedback.phase)

    with DdsActionClient(HIGH_FIVE, "high_five", domain_id=DOMAIN, prefix=prefix) as client:
        result = client.send_goal_and_wait(HighFiveGoal(target_height=0.3, hold_seconds=0),
                                           timeout=120.0, feedback_callback=feedback)
    assert result.status is S.SUCCEEDED and result.result.success
    assert phases == ["shifting", "unloading", "raising", "ready", "lowering", "reloading",
                      "shifting_back", "complete"]
    assert loop.controller.stance_legs == ["FL", "FR", "RL", "RR"]


def test_a_client_killed_with_the_foot_up_gets_the_foot_put_down(simulated: Any) -> None:
    loop, bridge, prefix = simulated
    client = ClientProcess(prefix, height=0.3, hold=60)
    try:
        goal_id = client.wait_for_line("accepted").split()[1]
        client.wait_for_line("phase ready")
        local = bridge.goal_handle(goal_id)
        killed_at = client.kill()
        wait_until(lambda: local.status in (S.CANCELING, S.CANCELED),
                   what="the server to cancel the goal")
        elapsed = time.monotonic() - killed_at
        result = local.get_result_async().result(timeout=120.0)
    finally:
        client.stop()
    assert elapsed < LEASE_S + LEASE_SLACK_S
    assert result.status is S.CANCELED
    assert result.result.message == ("canceled (canceled by client request): the foot is down "
                                     "and the robot is back on four feet")
    forces = loop.sim.foot_contact_forces()
    assert all(forces[leg][2] > 5.0 for leg in ("FL", "FR", "RL", "RR"))
