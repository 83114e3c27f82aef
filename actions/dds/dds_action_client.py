"""Sends goals to an action server in another process over DDS (ROS 2: ``ros2 action send_goal``).

:class:`DdsActionClient` has the methods of :class:`~actions.action_client.ActionClient`
(``wait_for_server``, ``send_goal_async``, ``cancel``, ``send_goal_and_wait``) and hands out the
framework's :class:`~actions.client_goal_handle.ClientGoalHandle` and futures, so code written
for a local client runs against a remote one. The differences: goal ids are UUIDs, every wait is
on the wall clock, and a server must first be discovered (``wait_for_server``).

A receive thread of the client takes the server's replies and resolves the futures; feedback
callbacks and the futures' done callbacks run on it (exceptions are logged). If the server dies
(its writers' liveliness lapses) or the client is closed, the futures still waiting fail with
:class:`ActionServerUnavailableError` or :class:`~actions.errors.ActionUsageError`.
"""

from __future__ import annotations

import atexit
import logging
import threading
import time
import uuid
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeoutError
from typing import Any

from actions.action_client import ActionTimeoutError
from actions.action_server import ActionServer
from actions.action_type import ActionType
from actions.behaviour import Behaviour
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.dds.goals_in_flight import GoalsInFlight, SentGoal
from actions.dds.payload_codec import check_json_action, encode_message
from actions.errors import ActionUsageError
from actions.goal_lifecycle import resolve
from actions.goal_record import GoalRecord
from actions.responses import CancelResponse, CancelReturnCode, FeedbackMessage, WrappedResult
from wbc.core.errors import ConfigurationError, WbcError
from wbc.core.validation import is_finite_real
from wbc.robot_io.dds.action_endpoints import (
    DEFAULT_INTERFACE,
    DEFAULT_PREFIX,
    ActionEndpoints,
    DdsError,
    check_lease,
)
from wbc.robot_io.dds.action_messages import CancelGoalRequest, SendGoalRequest
from wbc.robot_io.dds.domain_config import join_domain
from wbc.robot_io.dds.served_directory import ServedDirectory

logger = logging.getLogger(__name__)

#: How often the receive thread wakes without data, to check the server's liveliness [s].
WAKE_PERIOD_S = 0.05
#: Longest ``close`` waits for the receive thread (a callback may block) [s].
CLOSE_TIMEOUT_S = 5.0
#: How often ``wait_for_server`` checks the matching [s].
MATCH_POLL_S = 0.005
_TAKE_MAX = 256


class ActionServerUnavailableError(WbcError, ConnectionError):
    """No action server matched in time, or the server was lost while goals were in flight."""


class _ServedElsewhere:
    """Stands in for the runner a client-side :class:`ActionServer` view registers with."""

    def add_server(self, server: ActionServer) -> None:
        """Nothing to register: the server runs in another process."""


def _runs_in_the_server_process() -> Behaviour[Any, Any, Any]:
    raise ActionUsageError("this action's behaviours run in the server's process, not here")


class DdsActionClient:
    """Client of one named action served over DDS. Every method may be called from any thread.

    Args:
        action_type: The interface, e.g. ``HIGH_FIVE`` (rclpy: ``ActionClient(node, HighFive,
            "high_five")``).
        action_name: The server's name, e.g. ``"high_five"``.
        domain_id: The DDS domain, 0 to 232.
        interface: The network interface (default ``lo``).
        prefix: The topics' prefix (see :mod:`wbc.robot_io.dds.action_endpoints`).
        lease_s: Liveliness lease [s] this client offers: if it dies, the server cancels its
            goals within this time. Must not exceed the server's ``client_lease_s``.

    Raises:
        ConfigurationError: An invalid argument, or an interface whose messages are not
            Message dataclasses.
    """

    def __init__(self, action_type: ActionType, action_name: str, *, domain_id: int = 0,
                 interface: str = DEFAULT_INTERFACE, prefix: str = DEFAULT_PREFIX,
                 lease_s: float = 0.5) -> None:
        check_json_action(action_type, what=f"DdsActionClient of {action_name!r}")
        self.lease_s = check_lease("lease_s", lease_s)
        self._view = ActionServer(_ServedElsewhere(), action_type, action_name,
                                  _runs_in_the_server_process)
        self.prefix = prefix
        self._client_id = str(uuid.uuid4())
        self._lock = threading.Lock()  # guards _closing
        self._goals = GoalsInFlight(self._client_id, action_type)
        self._closing = False
        self._closed = threading.Event()
        self._closed_in_callback = False
        self._server_alive = False
        self._dds = join_domain(interface, domain_id=domain_id)
        try:
            self._ends = ActionEndpoints.for_client(self._dds, prefix, action_name,
                                                    lease_s=self.lease_s)
            self._directory = ServedDirectory.reader(self._dds, prefix)
        except BaseException:
            self._dds.close()
            raise
        self._thread = threading.Thread(target=self._receive, daemon=True,
                                        name=f"dds-action-client:{action_name}")
        self._thread.start()
        atexit.register(self.close)  # delete the readers before the interpreter goes

    @property
    def action_name(self) -> str:
        """The action this client talks to."""
        return self._view.action_name

    @property
    def action_type(self) -> ActionType:
        """The action's interface (``.Goal`` builds a goal)."""
        return self._view.action_type

    @property
    def client_id(self) -> str:
        """This client's id (a UUID) on the wire."""
        return self._client_id

    def server_is_ready(self) -> bool:
        """Whether every endpoint of this client matches a server's."""
        return not self._closing and not self._ends.unmatched()

    def wait_for_server(self, timeout_sec: float | None = None) -> bool:
        """Wait until a server matches (rclpy's ``wait_for_server``).

        Args:
            timeout_sec: Longest wait [s, wall-clock]; ``None`` waits for ever.

        Returns:
            Whether a server matched in time.
        """
        _check_seconds("timeout_sec", timeout_sec, allow_none=True, allow_zero=True)
        deadline = None if timeout_sec is None else time.monotonic() + timeout_sec
        while not self.server_is_ready():
            if self._closing or (deadline is not None and time.monotonic() >= deadline):
                return False
            self._closed.wait(MATCH_POLL_S)
        return True

    def send_goal_async(self, goal: Any,
                        feedback_callback: Callable[[FeedbackMessage], None] | None = None
                        ) -> Future[ClientGoalHandle]:
        """Send a goal; the future resolves when the server accepts or rejects it.

        Args:
            goal: A message of the action's goal type, checked and copied now.
            feedback_callback: Called on the receive thread with each :class:`FeedbackMessage`.

        Raises:
            ConfigurationError: ``goal`` is not the goal type or a field is invalid (named).
            ActionServerUnavailableError: No server matches now (call ``wait_for_server``).
            ActionUsageError: The client is closed.
        """
        self._check_open()
        if feedback_callback is not None and not callable(feedback_callback):
            raise ConfigurationError(
                f"feedback_callback must be callable or None; received {feedback_callback!r}")
        text = encode_message(goal, self.action_type.goal_type,
                              what=f"the goal of '{self.action_name}'")
        if not self.server_is_ready():
            raise ActionServerUnavailableError(
                self.unavailable_reason() + "; call wait_for_server(timeout_sec) first")
        goal_id = str(uuid.uuid4())
        record = GoalRecord(goal_id, self._view, goal.validated_copy(), feedback_callback)
        sent = SentGoal(record, ClientGoalHandle(self, record), Future())
        self._goals.add_goal(sent)
        try:
            self._ends.write("send_goal_request", SendGoalRequest(
                self._client_id, goal_id, self.action_name, self.action_type.type_name, text))
        except DdsError as err:
            self._goals.forget(goal_id=goal_id)
            raise ActionServerUnavailableError(
                f"sending goal {goal_id} to '{self.action_name}' failed: {err}") from err
        return sent.handle_future

    def cancel(self, goal_handle: ClientGoalHandle) -> Future[CancelResponse]:
        """Ask to cancel a goal; same as ``goal_handle.cancel_goal_async()``."""
        return goal_handle.cancel_goal_async()

    def submit_cancel(self, record: GoalRecord) -> Future[CancelResponse]:
        """Send a cancel request for ``record``'s goal (what ``ClientGoalHandle`` calls)."""
        if record.rejection is not None:
            future: Future[CancelResponse] = Future()
            resolve(future, CancelResponse(record.goal_id, CancelReturnCode.ERROR_UNKNOWN_GOAL_ID,
                                           "the goal was rejected; nothing to cancel"))
            return future
        self._check_open()
        request_id = str(uuid.uuid4())
        future = self._goals.add_cancel(request_id)
        try:
            self._ends.write("cancel_goal_request", CancelGoalRequest(
                self._client_id, request_id, record.goal_id, self.action_name))
        except DdsError as err:
            self._goals.forget(request_id=request_id)
            future.set_exception(ActionServerUnavailableError(
                f"sending the cancel of goal {record.goal_id} failed: {err}"))
        return future

    def send_goal_and_wait(self, goal: Any, timeout: float | None = None,
                           feedback_callback: Callable[[FeedbackMessage], None] | None = None,
                           *, server_timeout_s: float = 5.0) -> WrappedResult:
        """Wait for a server, send a goal and block until it ends (wall-clock).

        Args:
            goal: A message of the action's goal type.
            timeout: Longest wait for the whole call [s, wall-clock]; ``None``: no limit.
            feedback_callback: As in :meth:`send_goal_async`.
            server_timeout_s: Longest wait for a server to match [s] (within ``timeout``).

        Returns:
            The goal's terminal status and result.

        Raises:
            ActionServerUnavailableError: No server matched in time (the message says what
                was seen on the domain), or the server was lost during the goal.
            GoalRejectedError: The goal was rejected (code and message attached).
            ActionTimeoutError: ``timeout`` expired; the goal is NOT cancelled (cancel it with
                ``client.cancel(err.goal_handle)``).
            ConfigurationError: An invalid goal or argument.
        """
        _check_seconds("timeout", timeout, allow_none=True)
        _check_seconds("server_timeout_s", server_timeout_s, allow_none=False)
        start = time.monotonic()

        def remaining() -> float | None:
            return None if timeout is None else max(0.0, start + timeout - time.monotonic())

        if not self.server_is_ready():
            wait_s = server_timeout_s if timeout is None else min(server_timeout_s, timeout)
            if not self.wait_for_server(wait_s):
                raise ActionServerUnavailableError(self.unavailable_reason(wait_s))
        handle_future = self.send_goal_async(goal, feedback_callback)
        handle: ClientGoalHandle | None = None
        try:
            try:
                handle = handle_future.result(timeout=remaining())
            except FutureTimeoutError:
                raise ActionTimeoutError(
                    f"the goal request to '{self.action_name}' was not answered within "
                    f"{timeout:g} s of wall-clock time; the server may still accept it (it has "
                    "NOT been withdrawn): use err.goal_handle_future to cancel it once accepted"
                ) from None
            if handle.rejection is not None:
                raise GoalRejectedError(handle.goal_id, handle.action_name, handle.rejection)
            try:
                return handle.get_result_async().result(timeout=remaining())
            except FutureTimeoutError:
                raise ActionTimeoutError(
                    f"goal {handle.goal_id} ({self.action_name}) did not finish within "
                    f"{timeout:g} s of wall-clock time; it is still {handle.status.name} and has "
                    "NOT been cancelled: cancel it with client.cancel(err.goal_handle)") from None
        except ActionTimeoutError as err:
            err.goal_handle, err.goal_handle_future = handle, handle_future
            raise

    def unavailable_reason(self, waited_s: float = 0.0) -> str:
        """Why no server matches: what this client looks for, what matched, what is served."""
        names = self._ends.names
        text = (f"no action server '{self.action_name}' ({self.action_type.type_name}) matched "
                f"within {waited_s:g} s on DDS domain {self._dds.domain_id} (interface "
                f"{self._dds.interface!r}, topics {names.send_goal_request.rsplit('/', 2)[0]}/...)")
        missing = self._ends.unmatched()
        if len(missing) < len(self._ends.readers) + len(self._ends.writers):
            text += f"; endpoints not matched yet: {', '.join(missing)}"
        if self._ends.liveliness_refused("send_goal_request"):
            text += (f"; a server refused this client's liveliness lease_s={self.lease_s:g} s "
                     "(longer than the server's client_lease_s)")
        served = self._directory.entries()
        if served:
            return text + f"; action servers seen on this domain: {', '.join(served)}"
        return text + ("; no action server seen on this domain (is a DdsActionBridge polled on "
                       "the same domain id, interface and prefix?)")

    def close(self) -> None:
        """Stop the receive thread, fail the futures still waiting, delete the readers and
        writers (the server then cancels this client's goals). Idempotent."""
        atexit.unregister(self.close)
        with self._lock:
            if self._closing:
                return
            self._closing = True
        self._closed.set()
        self._ends.wake()
        if threading.current_thread() is self._thread:  # in a callback: the thread tears down
            self._closed_in_callback = True
            return
        self._thread.join(timeout=CLOSE_TIMEOUT_S)
        if self._thread.is_alive():  # a callback blocks: deleting its readers would crash it
            logger.error("the receive thread of '%s' did not stop within %g s (a callback "
                         "blocks); its DDS entities are left to the process exit",
                         self.action_name, CLOSE_TIMEOUT_S)
            return
        self._teardown()

    def __enter__(self) -> DdsActionClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- receive thread --------------------------------------------------------------------

    def _receive(self) -> None:
        ends = self._ends
        handlers = (("send_goal_response", self._goals.on_goal_response),
                    ("cancel_goal_response", self._goals.on_cancel_response),
                    ("feedback", self._goals.on_feedback),
                    ("status", self._goals.on_status),
                    ("result", self._goals.on_result))
        while not self._closing:
            try:
                ends.wait(WAKE_PERIOD_S)
                for role, handler in handlers:
                    for sample in ends.take(role, _TAKE_MAX):
                        if sample.sample_info.valid_data and not self._closing:
                            handler(sample)
                self._check_server()
            except Exception:  # the thread must outlive one bad sample
                logger.exception("the receive thread of '%s' failed a pass", self.action_name)
        if self._closed_in_callback:
            self._teardown()

    def _check_server(self) -> None:
        """Fail the goals in flight once the server's writers lose their liveliness."""
        alive = self._ends.alive_writers("result")
        if alive or not self._server_alive:
            self._server_alive = bool(alive)
            return
        self._server_alive = False
        self._goals.fail_all(lambda what: ActionServerUnavailableError(
            f"the action server of '{self.action_name}' was lost (its liveliness lease lapsed "
            f"or it closed) while {what}; the outcome is unknown"))

    def _teardown(self) -> None:
        self._goals.fail_all(lambda what: ActionUsageError(
            f"the DdsActionClient of '{self.action_name}' was closed while {what}; the server "
            "cancels the goals of a client that closes"))
        self._directory.close()
        self._ends.close()
        self._dds.close()

    def _check_open(self) -> None:
        if self._closing:
            raise ActionUsageError(f"the DdsActionClient of '{self.action_name}' is closed")


def _check_seconds(name: str, value: Any, *, allow_none: bool, allow_zero: bool = False) -> None:
    if value is None and allow_none:
        return
    if not is_finite_real(value) or value < 0 or (value == 0 and not allow_zero):
        low = ">= 0" if allow_zero else "> 0"
        valid = f"None or a finite number of seconds {low}" if allow_none else (
            f"a finite number of seconds {low}")
        raise ConfigurationError(f"{name} must be {valid}; received {value!r}")
