"""Runs the goals of one robot's action servers, one goal at a time, on the control tick.

ROS 2 analogue: the node + executor that host ``rclpy.action.ActionServer`` objects. Unlike
rclpy, nothing here runs in a thread of its own and there are no timers: every state change
happens inside :meth:`ActionRunner.tick`, called by the control loop with the simulated time,
so the same inputs give the same run (and the same :attr:`ActionRunner.event_log`).

One tick, in order:

1. Client requests, in arrival order: goal submissions are accepted or rejected (goal
   callback, then busy policy); accepted cancel requests move the goal to CANCELING and call
   ``behaviour.cancel`` right away.
2. If the robot is idle, the oldest ACCEPTED goal starts: EXECUTING, ``behaviour.start``.
3. The active goal's behaviour is stepped; its feedback is published, then its end (if any)
   is finalised. A goal still CANCELING ``max_unwind_s`` after its cancel is aborted.

Client callbacks (feedback callbacks, done callbacks of the futures) run on the ticking
thread, after the state change they report. Exceptions they raise are logged (``logging``)
and never break the tick.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any

from actions.action_server import ActionServer
from actions.busy_policy import BusyPolicy
from actions.client_goal_handle import ClientGoalHandle
from actions.errors import ActionUsageError
from actions.event_log import Event, EventLog
from actions.goal_lifecycle import CancelRequest, GoalLifecycle, GoalRequest, resolve
from actions.goal_record import GoalRecord
from actions.messages import Message
from actions.responses import CancelResponse, CancelReturnCode, FeedbackMessage
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.core.validation import is_finite_real

# BusyPolicy and Event are part of the runner's API: importable from here as they always were.
__all__ = ["ActionRunner", "BusyPolicy", "Event"]


class ActionRunner:
    """Owns the action servers of one robot and runs at most one goal at a time.

    Args:
        busy_policy: What to do with a goal that arrives while the robot is busy.
        spinner: A ``spin_once()`` callable that advances the control loop by one period and
            calls :meth:`tick`; same as calling :meth:`set_spinner` from this thread.
        event_log_maxlen: How many events to keep (oldest dropped first); ``None`` keeps all.

    Thread safety: clients may submit goals and cancels from any thread. :meth:`tick` and
    :meth:`shutdown` are serialised; calling either from inside a tick callback raises
    :class:`~actions.errors.ActionUsageError`.
    """

    def __init__(
        self,
        *,
        busy_policy: BusyPolicy = BusyPolicy.REJECT,
        spinner: Callable[[], object] | None = None,
        event_log_maxlen: int | None = 100_000,
    ) -> None:
        if not isinstance(busy_policy, BusyPolicy):
            valid = ", ".join(f"BusyPolicy.{policy.name}" for policy in BusyPolicy)
            raise ConfigurationError(
                f"busy_policy must be one of {valid}; received {busy_policy!r}"
            )
        self._events = EventLog(event_log_maxlen)
        self._goals = GoalLifecycle(busy_policy, self._events)
        self._servers: dict[str, ActionServer] = {}
        self._lock = threading.Lock()  # guards _requests, _shut_down, _next_id, _servers, spinner
        self._tick_lock = threading.Lock()  # serialises tick() and shutdown()
        self._tick_thread: int | None = None
        self._requests: list[GoalRequest | CancelRequest] = []
        self._next_id = 1
        self._tick_count = 0
        self._shut_down = False
        self._spinner: tuple[Callable[[], object], int] | None = None
        if spinner is not None:
            self.set_spinner(spinner)

    # --- configuration -------------------------------------------------------------------

    def add_server(self, server: ActionServer) -> None:
        """Register ``server`` (called by ``ActionServer.__init__``).

        Raises:
            ConfigurationError: Its name is already used on this runner.
        """
        with self._lock:
            if server.action_name in self._servers:
                raise ConfigurationError(
                    f"action name '{server.action_name}' is already served on this runner; "
                    f"names in use: {', '.join(sorted(self._servers))}"
                )
            self._servers[server.action_name] = server

    def server(self, action_name: str) -> ActionServer:
        """The server registered under ``action_name``.

        Raises:
            UnknownNameError: No such server; the message lists every served name.
        """
        with self._lock:
            server = self._servers.get(action_name)
            names = sorted(self._servers)
        if server is None:
            raise UnknownNameError(
                f"no action server named {action_name!r} on this runner; "
                f"served names: {', '.join(names) if names else '(none)'}"
            )
        return server

    @property
    def server_names(self) -> tuple[str, ...]:
        """Names of the registered servers, sorted."""
        with self._lock:
            return tuple(sorted(self._servers))

    def set_spinner(self, spin_once: Callable[[], object] | None) -> None:
        """Register the control loop's ``spin_once()`` for blocking calls on this thread.

        ``spin_once`` must advance the loop by one control period and call :meth:`tick`.
        ``ActionClient.send_goal_and_wait`` called from the thread that registered it drives
        it itself (like ``rclpy.spin_until_future_complete``), with its timeout in simulated
        seconds. Calls from other threads wait for whoever ticks. ``None`` unregisters.

        Raises:
            ConfigurationError: ``spin_once`` is neither callable nor ``None``.
        """
        if spin_once is not None and not callable(spin_once):
            raise ConfigurationError(f"spin_once must be callable or None; received {spin_once!r}")
        with self._lock:
            self._spinner = None if spin_once is None else (spin_once, threading.get_ident())

    def spinner_for_current_thread(self) -> Callable[[], object] | None:
        """The registered ``spin_once`` if this thread registered it, else ``None``."""
        with self._lock:
            spinner = self._spinner
        if spinner is None or spinner[1] != threading.get_ident():
            return None
        return spinner[0]

    # --- state ---------------------------------------------------------------------------

    @property
    def busy_policy(self) -> BusyPolicy:
        """What happens to a goal that arrives while the robot is busy."""
        return self._goals.busy_policy

    @property
    def now_s(self) -> float | None:
        """Simulated time [s] of the latest tick (or shutdown); ``None`` before the first."""
        return self._goals.now_s

    @property
    def tick_count(self) -> int:
        """How many ticks have run."""
        return self._tick_count

    @property
    def is_shut_down(self) -> bool:
        """Whether :meth:`shutdown` has been called."""
        return self._shut_down

    @property
    def active_goal_id(self) -> str | None:
        """The goal that is EXECUTING or CANCELING, if any."""
        active = self._goals.active
        return None if active is None else active.goal_id

    def active_goals(self) -> tuple[GoalRecord, ...]:
        """The goals not ended yet: the one EXECUTING or CANCELING first, if any, then those
        accepted and waiting to start, oldest first (a snapshot; the records are the runner's
        own, read them on the ticking thread)."""
        active = self._goals.active
        return (*(() if active is None else (active,)), *tuple(self._goals.queue))

    @property
    def queued_goal_ids(self) -> tuple[str, ...]:
        """Accepted goals waiting to start, oldest first."""
        return tuple(record.goal_id for record in tuple(self._goals.queue))

    @property
    def event_log(self) -> list[Event]:
        """A copy of the event log: ``(now_s, goal_id, event, detail)`` tuples in order.

        Events: ``accepted``, ``rejected``, ``executing``, ``canceling``, ``succeeded``,
        ``canceled``, ``aborted`` (the status changes; the terminal ones carry the result),
        ``feedback``, ``cancel_refused``, ``callback_error`` and ``shutdown`` (goal id "").
        """
        return self._events.snapshot()

    def in_tick_thread(self) -> bool:
        """Whether the calling thread is inside :meth:`tick` or :meth:`shutdown` (a callback)."""
        return self._tick_thread == threading.get_ident()

    # --- client entry points (used by ActionClient / ClientGoalHandle) ----------------------

    def submit_goal(
        self,
        server: ActionServer,
        goal: Any,
        feedback_callback: Callable[[FeedbackMessage], None] | None = None,
    ) -> Future[ClientGoalHandle]:
        """Queue a goal for the next tick. Thread-safe. Prefer ``ActionClient.send_goal_async``.

        The server works on a validated deep copy of a :class:`~actions.messages.Message`
        goal (:meth:`~actions.messages.Message.validated_copy`), so a goal filled field by
        field is checked here, as one built with keywords is at construction, and later
        changes to the caller's message do not reach the server.

        Returns:
            A future resolved with the goal's handle on the tick that accepts or rejects it
            (at once if the runner is shut down).

        Raises:
            ConfigurationError: ``goal`` is not the server's goal type, one of its fields
                has the wrong type or value (the message names it), or
                ``feedback_callback`` is not callable.
        """
        expected = server.action_type.goal_type
        if not isinstance(goal, expected):
            raise ConfigurationError(
                f"action '{server.action_name}' takes a {expected.__name__} goal; received "
                f"{goal!r} (type {type(goal).__name__})"
            )
        if isinstance(goal, Message):
            goal = goal.validated_copy()
        if feedback_callback is not None and not callable(feedback_callback):
            raise ConfigurationError(
                f"feedback_callback must be callable or None; received {feedback_callback!r}"
            )
        with self._lock:
            record = GoalRecord(str(self._next_id), server, goal, feedback_callback)
            self._next_id += 1
            request = GoalRequest(record, ClientGoalHandle(self, record), Future())
            shut_down = self._shut_down
            if not shut_down:
                self._requests.append(request)
        if shut_down:
            self._goals.reject(request, self._goals.shut_down_rejection())
        return request.future

    def submit_cancel(self, record: GoalRecord) -> Future[CancelResponse]:
        """Queue a cancel request for the next tick. Thread-safe.

        Prefer ``ClientGoalHandle.cancel_goal_async``. Answered at once if the goal was
        rejected or the runner is shut down.
        """
        future: Future[CancelResponse] = Future()
        with self._lock:
            shut_down = self._shut_down
            if record.rejection is None and not shut_down:
                self._requests.append(CancelRequest(record, future))
                return future
        if record.rejection is not None:
            code, why = CancelReturnCode.ERROR_UNKNOWN_GOAL_ID, "the goal was rejected"
        else:
            code, why = CancelReturnCode.ERROR_GOAL_TERMINATED, "the runner is shut down"
        resolve(future, CancelResponse(record.goal_id, code, f"{why}; nothing to cancel"))
        return future


    # --- ticking -------------------------------------------------------------------------

    def tick(self, now_s: float) -> None:
        """Process requests, start, step and finalise goals at simulated time ``now_s`` [s].

        After :meth:`shutdown` a tick only advances :attr:`now_s`.

        Raises:
            ConfigurationError: ``now_s`` is not finite or is earlier than the previous tick.
            ActionUsageError: Called from inside a tick callback.
        """
        self._refuse_reentry()
        with self._tick_lock:
            self._enter_tick(now_s)
            try:
                self._tick_count += 1
                goals = self._goals
                if self._shut_down:
                    return
                if not self._requests and goals.active is None and not goals.queue:
                    return  # idle: nothing to process, start or step
                if self._requests:  # a request appended meanwhile waits for the next tick
                    with self._lock:
                        requests, self._requests = self._requests, []
                    for request in requests:
                        if isinstance(request, GoalRequest):
                            self._goals.process_goal(request)
                        else:
                            self._goals.process_cancel(request)
                self._goals.start_next()
                self._goals.step_active()
            finally:
                self._tick_thread = None

    def shutdown(self, now_s: float) -> None:
        """End every unfinished goal ABORTED and refuse new goals. Idempotent.

        A started goal's behaviour gets ``cancel(now_s, "runner shut down at t=... s")`` so it
        can release the robot, then the goal ends at once with its ``abort_result``. Pending
        goal requests are rejected with ``RejectionCode.SHUT_DOWN``, as is every later one.

        Raises:
            ConfigurationError: ``now_s`` is not finite or is earlier than the previous tick.
            ActionUsageError: Called from inside a tick callback.
        """
        if self._shut_down:
            return
        self._refuse_reentry()
        with self._tick_lock:
            self._enter_tick(now_s)
            try:
                with self._lock:
                    if self._shut_down:
                        return
                    self._shut_down = True
                    requests, self._requests = self._requests, []
                reason = f"runner shut down at t={now_s:g} s"
                self._goals.log("", "shutdown", reason)
                self._goals.shut_down(requests, reason)
            finally:
                self._tick_thread = None

    def abort_goals(self, now_s: float, reason: str) -> None:
        """End the running goal and the queued ones ABORTED with ``reason`` (the running
        goal's behaviour is canceled first, so it can release the robot); later goals are
        processed as usual. Between ticks, on the ticking thread.

        Raises:
            ConfigurationError: ``now_s`` is not finite or is earlier than the previous tick.
            ActionUsageError: Called from inside a tick callback.
        """
        self._refuse_reentry()
        with self._tick_lock:
            self._enter_tick(now_s)
            try:
                if not self._shut_down:
                    self._goals.abort_all(reason)
            finally:
                self._tick_thread = None

    def _refuse_reentry(self) -> None:
        if self._tick_thread == threading.get_ident():
            raise ActionUsageError(
                "ActionRunner.tick/shutdown called from inside a tick callback; call it from "
                "the control loop, after the current tick returns"
            )

    def _enter_tick(self, now_s: float) -> None:
        """Check and record the tick's time; mark this thread as ticking (under the lock)."""
        # A float is the common case: checked without the numbers ABC.
        if not (type(now_s) is float and math.isfinite(now_s)) and not is_finite_real(now_s):
            raise ConfigurationError(f"now_s must be a finite time [s]; received {now_s!r}")
        previous = self._goals.now_s
        if previous is not None and now_s < previous:
            raise ConfigurationError(
                f"now_s must not go backwards: received {now_s!r} after {previous!r}"
            )
        self._goals.now_s = float(now_s)
        self._tick_thread = threading.get_ident()
