"""Serves the action servers of one runner over DDS (ROS 2: the action server's transport).

:class:`DdsActionBridge` takes the goal and cancel requests of DDS clients
(:class:`~actions.dds.dds_action_client.DdsActionClient`, in any process of the domain), hands
them to the runner's servers as a local client would, and publishes the responses, feedback,
status and results. It touches DDS and the runner only in :meth:`DdsActionBridge.poll`, called
by the control loop after each ``runner.tick``: nothing runs on DDS threads, and the runner's
callbacks (on the ticking thread) only queue work for the next poll.

A client that disappears (its process died, or it closed) has its goals canceled: its request
writers offer a short liveliness lease, and when that lapses its DDS instance becomes NOT_ALIVE
on the request readers. A cancel is the graceful stop the servers define (HighFive puts the
foot down, then the goal ends CANCELED; the runner aborts an unwind longer than the server's
``max_unwind_s``). A server whose cancel callback refuses keeps running the goal to its end.
"""

from __future__ import annotations

import atexit
import logging
import math
import re
import threading
from collections import OrderedDict, deque
from collections.abc import Callable, Iterable
from concurrent.futures import Future
from dataclasses import dataclass, field
from functools import partial
from typing import Any

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner
from actions.client_goal_handle import ClientGoalHandle
from actions.dds.goal_request_check import TransportRejectionCode, check_goal_request
from actions.dds.payload_codec import check_json_action, encode_message
from actions.goal_status import GoalStatus
from actions.responses import CancelResponse, CancelReturnCode, FeedbackMessage, Rejection
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.action_endpoints import (
    DEFAULT_INTERFACE,
    DEFAULT_PREFIX,
    ActionEndpoints,
    DdsError,
    SampleWatch,
    check_lease,
    check_name,
    is_alive,
    unregister_instance,
    write_logged,
)
from wbc.robot_io.dds.action_messages import (
    CancelGoalRequest,
    CancelGoalResponse,
    GoalFeedback,
    GoalResult,
    GoalStatusUpdate,
    SendGoalRequest,
    SendGoalResponse,
)
from wbc.robot_io.dds.domain_config import join_domain
from wbc.robot_io.dds.served_directory import ServedDirectory

logger = logging.getLogger(__name__)

#: Most requests taken from one reader in one poll; the rest wait for the next.
TAKE_PER_POLL = 64
_LOCAL_LABEL = re.compile(r"\bgoal (\d+) \(")


@dataclass(eq=False)
class _Served:
    name: str
    client: ActionClient
    ends: ActionEndpoints


@dataclass(eq=False)
class _RemoteGoal:
    goal_id: str  # the client's UUID
    client_id: str
    served: _Served
    handle: ClientGoalHandle | None = None  # the runner's handle, once processed
    published: GoalStatus | None = None
    client_gone: bool = False
    deferred_cancels: list[CancelGoalRequest] = field(default_factory=list)


class DdsActionBridge:
    """Exposes the action servers of a runner to DDS clients.

    Args:
        runner: The runner whose servers to expose, or an object holding one as ``.runner``
            (a :class:`~actions.robot.control_loop.ControlLoop`).
        domain_id: The DDS domain, 0 to 232.
        interface: The network interface (default ``lo``).
        prefix: The topics' prefix (see :mod:`wbc.robot_io.dds.action_endpoints`).
        actions: The action names to expose; default: every server registered on the runner
            now (servers added later are not exposed).
        lease_s: Liveliness lease [s] this bridge's writers offer (clients notice a dead server
            within it).
        client_lease_s: Longest liveliness lease [s] a client may offer: a dead client's goals
            are canceled within its lease, so within this; clients offering more do not match.
        retain_finished: How many finished goals keep their status and result on the topics
            (and answer cancels with "already ended").

    Raises:
        ConfigurationError: An invalid argument, an action that is not served or whose
            messages are not Message dataclasses, or a domain that cannot be configured.
    """

    def __init__(self, runner: Any, *, domain_id: int = 0, interface: str = DEFAULT_INTERFACE,
                 prefix: str = DEFAULT_PREFIX, actions: Iterable[str] | None = None,
                 lease_s: float = 0.5, client_lease_s: float = 1.0,
                 retain_finished: int = 32) -> None:
        held = runner if isinstance(runner, ActionRunner) else getattr(runner, "runner", None)
        if not isinstance(held, ActionRunner):
            raise ConfigurationError(
                f"runner must be an ActionRunner or hold one as .runner (e.g. a ControlLoop); "
                f"received {runner!r}")
        self._runner = held
        self.prefix = check_name("prefix", prefix)
        lease_s = check_lease("lease_s", lease_s)
        client_lease_s = check_lease("client_lease_s", client_lease_s)
        if type(retain_finished) is not int or retain_finished < 1:
            raise ConfigurationError(
                f"retain_finished must be an int >= 1; received {retain_finished!r}")
        self._retain = retain_finished
        names = held.server_names if actions is None else tuple(actions)
        clients = [ActionClient(held, name) for name in names]  # UnknownNameError lists names
        for client in clients:
            check_json_action(client.action_type, what=f"action '{client.action_name}'")
        self._live: dict[str, _RemoteGoal] = {}
        self._finished: OrderedDict[str, _RemoteGoal] = OrderedDict()
        self._uuid_of_local: dict[str, str] = {}
        self._pending: deque[Callable[[], None]] = deque()  # queued by runner callbacks
        self._lock = threading.Lock()  # serialises poll() and close()
        self._served: dict[str, _Served] = {}
        self._directory: ServedDirectory | None = None
        self._requests: SampleWatch | None = None
        self._dds = join_domain(interface, domain_id=domain_id)
        try:
            self._requests = SampleWatch(self._dds.participant)  # every request reader
            for client in clients:
                ends = ActionEndpoints.for_server(self._dds, self.prefix, client.action_name,
                                                  lease_s=lease_s, client_lease_s=client_lease_s)
                self._served[client.action_name] = _Served(client.action_name, client, ends)
                self._requests.watch(ends)
            self._directory = ServedDirectory.publish(
                self._dds, self.prefix, {name: served.client.action_type.type_name
                                         for name, served in self._served.items()},
                lease_s=lease_s)
        except BaseException:
            self.close()
            raise
        atexit.register(self.close)  # delete the readers before the interpreter goes

    @property
    def action_names(self) -> tuple[str, ...]:
        """The actions served over DDS, sorted."""
        return tuple(sorted(self._served))

    @property
    def domain_id(self) -> int:
        """The DDS domain."""
        return self._dds.domain_id

    def goal_handle(self, goal_id: str) -> ClientGoalHandle | None:
        """The runner's handle of a goal received over DDS (by the client's UUID), while it
        runs and for ``retain_finished`` goals after; ``None`` if unknown or not processed."""
        remote = self._live.get(goal_id) or self._finished.get(goal_id)
        return None if remote is None else remote.handle

    def poll(self) -> None:
        """Take pending requests without blocking, hand them to the servers, publish what the
        runner produced since the last poll. Call it on the control loop's thread, after each
        ``runner.tick`` (a request taken now is processed on the next tick). DDS errors are
        logged, never raised into the loop; after :meth:`close` it does nothing.
        """
        with self._lock:
            if self._dds.is_closed:
                return
            if self._requests is None or self._requests.pending():
                for served in self._served.values():
                    self._take(served, "send_goal_request", self._on_goal_request)
                    self._take(served, "cancel_goal_request", self._on_cancel_request)
            while self._pending:
                try:
                    self._pending.popleft()()
                except Exception:  # nothing of the bridge may stop the control loop
                    logger.exception("DdsActionBridge: a queued publication failed")
            self._publish_statuses()

    def tick_hook(self, loop: object, output: object) -> None:
        """:meth:`poll` as a ControlLoop tick hook: ``loop.hooks.append(bridge.tick_hook)``."""
        self.poll()

    def close(self) -> None:
        """Cancel the goals of DDS clients still running (the clients can no longer), delete
        the readers and writers and leave the domain. Idempotent; any thread (it waits for a
        poll in progress)."""
        atexit.unregister(self.close)
        with self._lock:
            if self._dds.is_closed:
                return
            for remote in list(self._live.values()):
                if remote.handle is not None and not remote.handle.status.is_terminal:
                    remote.handle.cancel_goal_async()
            if self._directory is not None:
                self._directory.close()
            if self._requests is not None:
                self._requests.close()
            for served in self._served.values():
                served.ends.close()
            self._dds.close()

    def __enter__(self) -> DdsActionBridge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _take(self, served: _Served, role: str, handler: Callable[[_Served, Any], None]) -> None:
        gone: set[str] = set()
        try:
            samples = served.ends.take(role, TAKE_PER_POLL)
        except DdsError:
            logger.exception("taking %s of '%s' failed", role, served.name)
            return
        for sample in samples:
            info = sample.sample_info
            if not is_alive(sample):
                gone.add((sample if info.valid_data else sample.key_sample).client_id)
            elif info.valid_data:
                handler(served, sample)
        for client_id in gone:
            self._client_gone(served, client_id)

    def _on_goal_request(self, served: _Served, request: SendGoalRequest) -> None:
        goal_id = request.goal_id
        checked = check_goal_request(
            request, action_name=served.name, action_type=served.client.action_type,
            topic=served.ends.names.send_goal_request, served_names=self._served,
            used_ids=self._live.keys() | self._finished.keys())
        remote = _RemoteGoal(goal_id, request.client_id, served)
        rejection = checked.rejection
        if rejection is None:
            try:
                future = served.client.send_goal_async(checked.goal,
                                                       partial(self._on_feedback, remote))
            except ConfigurationError as err:
                rejection = Rejection(TransportRejectionCode.MALFORMED_GOAL, str(err))
        if rejection is not None:
            logger.warning("goal %s for '%s' rejected: %s", goal_id, served.name,
                           rejection.message)
            self._respond_goal(served, request.client_id, goal_id, rejection)
            return
        self._live[goal_id] = remote
        future.add_done_callback(
            lambda done: self._pending.append(partial(self._goal_processed, remote, done)))

    def _goal_processed(self, remote: _RemoteGoal, future: Future[ClientGoalHandle]) -> None:
        handle = future.result()
        served = remote.served
        if not handle.accepted:
            del self._live[remote.goal_id]
            self._respond_goal(served, remote.client_id, remote.goal_id, handle.rejection)
            for request in remote.deferred_cancels:
                self._respond_cancel(served, request, CancelResponse(
                    request.goal_id, CancelReturnCode.ERROR_UNKNOWN_GOAL_ID,
                    f"goal {request.goal_id} was rejected; nothing to cancel"))
            return
        remote.handle = handle
        self._uuid_of_local[handle.goal_id] = remote.goal_id
        self._respond_goal(served, remote.client_id, remote.goal_id, None)
        handle.get_result_async().add_done_callback(
            lambda done: self._pending.append(partial(self._publish_result, remote, done)))
        for request in remote.deferred_cancels:
            self._submit_cancel(remote, handle, request)
        if remote.client_gone:
            self._cancel_for_gone_client(remote)

    def _on_cancel_request(self, served: _Served, request: CancelGoalRequest) -> None:
        remote = self._live.get(request.goal_id) or self._finished.get(request.goal_id)
        if remote is None or remote.served is not served:
            self._respond_cancel(served, request, CancelResponse(
                request.goal_id, CancelReturnCode.ERROR_UNKNOWN_GOAL_ID,
                f"no goal {request.goal_id} on action '{served.name}': never received, "
                f"rejected, or ended more than {self._retain} goals ago"))
        elif remote.handle is None:  # its goal request waits for the next tick
            remote.deferred_cancels.append(request)
        else:
            self._submit_cancel(remote, remote.handle, request)

    def _submit_cancel(self, remote: _RemoteGoal, handle: ClientGoalHandle,
                       request: CancelGoalRequest) -> None:
        future = handle.cancel_goal_async()
        future.add_done_callback(lambda done: self._pending.append(
            partial(self._respond_cancel, remote.served, request, done.result())))

    def _client_gone(self, served: _Served, client_id: str) -> None:
        """Cancel the goals of a client whose writers lost liveliness (or were deleted)."""
        ends = served.ends  # forget its responses: nobody will read them
        unregister_instance(ends, "send_goal_response",
                            SendGoalResponse(client_id, "", "", False, 0, "", 0.0))
        unregister_instance(ends, "cancel_goal_response",
                            CancelGoalResponse(client_id, "", "", "", 0, "", 0.0))
        for remote in list(self._live.values()):
            if remote.served is served and remote.client_id == client_id and (
                    not remote.client_gone):
                remote.client_gone = True
                if remote.handle is not None:
                    self._cancel_for_gone_client(remote)

    def _cancel_for_gone_client(self, remote: _RemoteGoal) -> None:
        handle = remote.handle
        if handle is None or handle.status.is_terminal:
            return
        logger.warning("client %s of goal %s (%s) is gone (liveliness lost or closed): "
                       "canceling the goal", remote.client_id, remote.goal_id, remote.served.name)

        def answered(done: Future[CancelResponse]) -> None:
            response = done.result()
            if not response.accepted:
                logger.warning("cancel of goal %s (client gone) refused: %s; it runs to its "
                               "end", remote.goal_id, response.message)

        handle.cancel_goal_async().add_done_callback(answered)

    def _on_feedback(self, remote: _RemoteGoal, message: FeedbackMessage) -> None:
        """Feedback callback, on the ticking thread: encode now, write at the next poll."""
        served = remote.served
        try:
            text = encode_message(message.feedback, served.client.action_type.feedback_type,
                                  what=f"feedback of goal {remote.goal_id}")
        except ConfigurationError:
            logger.exception("feedback of goal %s not sent", remote.goal_id)
            return
        sample = GoalFeedback(remote.goal_id, served.name, text, self._now_s())
        self._pending.append(partial(write_logged, served.ends, "feedback", sample))

    def _publish_result(self, remote: _RemoteGoal, future: Future[Any]) -> None:
        wrapped = future.result()
        action_type = remote.served.client.action_type
        try:
            text = encode_message(wrapped.result, action_type.result_type,
                                  what=f"result of goal {remote.goal_id}")
        except ConfigurationError as err:
            logger.exception("result of goal %s cannot be sent as it is", remote.goal_id)
            text = encode_message(action_type.failure(f"the result could not be sent: {err}"),
                                  action_type.result_type, what="failure result")
        write_logged(remote.served.ends, "result", GoalResult(
            remote.goal_id, remote.served.name, int(wrapped.status), text, self._now_s()))

    def _publish_statuses(self) -> None:
        for remote in list(self._live.values()):
            handle = remote.handle
            if handle is None:
                continue
            status = handle.status
            if status != remote.published:
                remote.published = status
                write_logged(remote.served.ends, "status", GoalStatusUpdate(
                    remote.goal_id, remote.served.name, int(status), self._now_s()))
            if status.is_terminal:
                self._retire(remote)

    def _retire(self, remote: _RemoteGoal) -> None:
        del self._live[remote.goal_id]
        self._finished[remote.goal_id] = remote
        while len(self._finished) > self._retain:
            _, old = self._finished.popitem(last=False)
            if old.handle is not None:
                self._uuid_of_local.pop(old.handle.goal_id, None)
            ends = old.served.ends
            unregister_instance(ends, "status", GoalStatusUpdate(old.goal_id, "", 0, 0.0))
            unregister_instance(ends, "result", GoalResult(old.goal_id, "", 0, "", 0.0))

    def _respond_goal(self, served: _Served, client_id: str, goal_id: str,
                      rejection: Rejection | None) -> None:
        code, message = (0, "") if rejection is None else (
            int(rejection.code), self._wire_text(rejection.message))
        write_logged(served.ends, "send_goal_response", SendGoalResponse(
            client_id, goal_id, served.name, rejection is None, code, message, self._now_s()))

    def _respond_cancel(self, served: _Served, request: CancelGoalRequest,
                        response: CancelResponse) -> None:
        write_logged(served.ends, "cancel_goal_response", CancelGoalResponse(
            request.client_id, request.request_id, request.goal_id, served.name,
            int(response.return_code), self._wire_text(response.message), self._now_s()))

    def _wire_text(self, text: str) -> str:
        """``text`` with the runner's goal labels (``goal 3 (high_five)``) in clients' UUIDs."""
        return _LOCAL_LABEL.sub(
            lambda m: f"goal {self._uuid_of_local.get(m.group(1), m.group(1))} (", text)

    def _now_s(self) -> float:
        now = self._runner.now_s
        return math.nan if now is None else now

