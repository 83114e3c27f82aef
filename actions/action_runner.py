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

import logging
import math
import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, InvalidStateError
from enum import Enum
from typing import TYPE_CHECKING, Any, NamedTuple

from actions.behaviour import StepResult
from actions.client_goal_handle import ClientGoalHandle
from actions.errors import ActionUsageError
from actions.goal_record import GoalRecord
from actions.goal_status import GoalStatus, check_transition, legal_next_statuses
from actions.messages import Message
from actions.responses import (
    CancelResponse,
    CancelReturnCode,
    FeedbackMessage,
    Rejection,
    RejectionCode,
    WrappedResult,
)
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.core.validation import is_finite_real

if TYPE_CHECKING:
    from actions.action_server import ActionServer

logger = logging.getLogger(__name__)

CANCELED_BY_CLIENT = "canceled by client request"


class BusyPolicy(Enum):
    """What a robot that is already running a goal does with a new one.

    Busy means: a goal is EXECUTING or CANCELING, or an accepted goal waits to start.
    """

    REJECT = "reject"
    """Reject the new goal (``RejectionCode.BUSY``), naming the running goal. The default."""
    PREEMPT = "preempt"
    """Accept the new goal and cancel the running one with reason ``"preempted by goal <id>
    (<action>)"`` (its server's cancel callback is not consulted). It unwinds, bounded by
    its server's ``max_unwind_s``; when its behaviour reports CANCELED, the goal ends ABORTED
    with ``abort_result("preempted by goal <id> (<action>)")``. (If the behaviour itself
    reports ABORTED, its own result stands; an unwind timeout's message names the
    preemption.) The new goal stays ACCEPTED and starts EXECUTING on the tick after the old
    one ended. A goal still waiting to start is aborted at once, with ``"preempted by goal
    <id> (<action>) before it started"``; it never runs. A goal already CANCELING at its
    client's request ends as that request says."""


class Event(NamedTuple):
    """One entry of the event log."""

    now_s: float
    goal_id: str
    event: str
    detail: str


class _CancelRequest(NamedTuple):
    record: GoalRecord
    future: Future[CancelResponse]


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
        spinner: Callable[[], None] | None = None,
        event_log_maxlen: int | None = 100_000,
    ) -> None:
        if not isinstance(busy_policy, BusyPolicy):
            valid = ", ".join(f"BusyPolicy.{policy.name}" for policy in BusyPolicy)
            raise ConfigurationError(
                f"busy_policy must be one of {valid}; received {busy_policy!r}"
            )
        if event_log_maxlen is not None and (
            not isinstance(event_log_maxlen, int) or event_log_maxlen < 1
        ):
            raise ConfigurationError(
                f"event_log_maxlen must be None or an int >= 1; received {event_log_maxlen!r}"
            )
        self._busy_policy = busy_policy
        self._servers: dict[str, ActionServer] = {}
        self._lock = threading.Lock()  # guards _requests, _shut_down, _next_id, _servers, spinner
        self._tick_lock = threading.Lock()  # serialises tick() and shutdown()
        self._events_lock = threading.Lock()
        self._tick_thread: int | None = None
        self._requests: list[GoalRecord | _CancelRequest] = []
        self._queue: deque[GoalRecord] = deque()
        self._active: GoalRecord | None = None
        self._events: deque[Event] = deque(maxlen=event_log_maxlen)
        self._next_id = 1
        self._now_s: float | None = None
        self._tick_count = 0
        self._shut_down = False
        self._spinner: tuple[Callable[[], None], int] | None = None
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

    def set_spinner(self, spin_once: Callable[[], None] | None) -> None:
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

    def spinner_for_current_thread(self) -> Callable[[], None] | None:
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
        return self._busy_policy

    @property
    def now_s(self) -> float | None:
        """Simulated time [s] of the latest tick (or shutdown); ``None`` before the first."""
        return self._now_s

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
        active = self._active
        return None if active is None else active.goal_id

    @property
    def queued_goal_ids(self) -> tuple[str, ...]:
        """Accepted goals waiting to start, oldest first."""
        return tuple(record.goal_id for record in tuple(self._queue))

    @property
    def event_log(self) -> list[Event]:
        """A copy of the event log: ``(now_s, goal_id, event, detail)`` tuples in order.

        Events: ``accepted``, ``rejected``, ``executing``, ``canceling``, ``succeeded``,
        ``canceled``, ``aborted`` (the status changes; the terminal ones carry the result),
        ``feedback``, ``cancel_refused``, ``callback_error`` and ``shutdown`` (goal id "").
        """
        with self._events_lock:
            return list(self._events)

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
            record.handle = ClientGoalHandle(self, record)
            shut_down = self._shut_down
            if not shut_down:
                self._requests.append(record)
        if shut_down:
            self._reject(record, self._shut_down_rejection())
        return record.handle_future

    def submit_cancel(self, record: GoalRecord) -> Future[CancelResponse]:
        """Queue a cancel request for the next tick. Thread-safe.

        Prefer ``ClientGoalHandle.cancel_goal_async``. Answered at once if the goal was
        rejected or the runner is shut down.
        """
        future: Future[CancelResponse] = Future()
        with self._lock:
            shut_down = self._shut_down
            if record.rejection is None and not shut_down:
                self._requests.append(_CancelRequest(record, future))
                return future
        if record.rejection is not None:
            code, why = CancelReturnCode.ERROR_UNKNOWN_GOAL_ID, "the goal was rejected"
        else:
            code, why = CancelReturnCode.ERROR_GOAL_TERMINATED, "the runner is shut down"
        _resolve(future, CancelResponse(record.goal_id, code, f"{why}; nothing to cancel"))
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
                if self._shut_down:
                    return
                if self._requests:  # a request appended meanwhile waits for the next tick
                    with self._lock:
                        requests, self._requests = self._requests, []
                    for request in requests:
                        if isinstance(request, GoalRecord):
                            self._process_goal_request(request)
                        else:
                            self._process_cancel_request(request)
                self._start_next()
                self._step_active()
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
                self._shut_down_now(now_s)
            finally:
                self._tick_thread = None

    def _shut_down_now(self, now_s: float) -> None:
        """The body of :meth:`shutdown`, inside the tick section."""
        with self._lock:
            if self._shut_down:
                return
            self._shut_down = True
            requests, self._requests = self._requests, []
        reason = f"runner shut down at t={now_s:g} s"
        self._log("", "shutdown", reason)
        for request in requests:
            if isinstance(request, GoalRecord):
                self._reject(request, self._shut_down_rejection())
        active = self._active
        if active is not None:
            if active.status == GoalStatus.EXECUTING:
                self._call_cancel(active, reason)
            if self._active is active:
                self._abort(active, f"{reason} while the goal was {active.status.name}")
        while self._queue:
            self._abort(self._queue.popleft(), f"{reason} before the goal started")
        for request in requests:
            if isinstance(request, _CancelRequest):
                self._process_cancel_request(request)

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
        if self._now_s is not None and now_s < self._now_s:
            raise ConfigurationError(
                f"now_s must not go backwards: received {now_s!r} after {self._now_s!r}"
            )
        self._now_s = float(now_s)
        self._tick_thread = threading.get_ident()

    # --- requests ------------------------------------------------------------------------

    def _process_goal_request(self, record: GoalRecord) -> None:
        server = record.server
        busy = self._active is not None or bool(self._queue)
        rejection = server.evaluate_goal(record.goal)
        if rejection is None and busy and self._busy_policy is BusyPolicy.REJECT:
            rejection = self._busy_rejection()
        if rejection is None:
            try:
                record.behaviour = server.create_behaviour()
            except Exception as err:
                logger.exception("behaviour factory of '%s' raised", server.action_name)
                rejection = Rejection(
                    RejectionCode.CALLBACK_ERROR,
                    f"behaviour factory of '{server.action_name}' raised "
                    f"{type(err).__name__}: {err}",
                )
        if rejection is not None:
            self._reject(record, rejection)
            return
        self._set_status(record, GoalStatus.ACCEPTED)
        if busy:
            self._preempt_for(record)
        self._queue.append(record)
        _resolve(record.handle_future, record.handle)

    def _busy_rejection(self) -> Rejection:
        running = self._active if self._active is not None else self._queue[0]
        return Rejection(
            RejectionCode.BUSY,
            f"robot busy: {running.label} is {running.status.name} and the busy policy is "
            "REJECT; cancel that goal or wait for it to end, or use BusyPolicy.PREEMPT",
        )

    def _shut_down_rejection(self) -> Rejection:
        return Rejection(
            RejectionCode.SHUT_DOWN,
            f"the action runner was shut down at t={self._now_s:g} s; it accepts no new goals",
        )

    def _preempt_for(self, record: GoalRecord) -> None:
        reason = f"preempted by {record.label}"
        while self._queue:
            self._abort(self._queue.popleft(), f"{reason} before it started")
        active = self._active
        if active is not None and active.status == GoalStatus.EXECUTING:
            active.preempted_by = reason
            self._begin_cancel(active, reason)

    def _process_cancel_request(self, request: _CancelRequest) -> None:
        record = request.record
        if record.status.is_terminal:
            code = CancelReturnCode.ERROR_GOAL_TERMINATED
            message = f"{record.label} already ended {record.status.name}"
        elif record.status == GoalStatus.CANCELING:
            code, message = CancelReturnCode.ERROR_NONE, f"{record.label} is already canceling"
        else:
            refusal = record.server.evaluate_cancel(record.goal_id, record.goal)
            if refusal is None:
                self._begin_cancel(record, CANCELED_BY_CLIENT)
                code, message = CancelReturnCode.ERROR_NONE, f"{record.label} is canceling"
            else:
                self._log(record.goal_id, "cancel_refused", refusal)
                code, message = CancelReturnCode.ERROR_REJECTED, refusal
        _resolve(request.future, CancelResponse(record.goal_id, code, message))

    # --- goal lifecycle ------------------------------------------------------------------

    def _begin_cancel(self, record: GoalRecord, reason: str) -> None:
        self._set_status(record, GoalStatus.CANCELING, reason)
        record.cancel_reason = reason
        record.cancel_requested_s = self._now_s
        if record is not self._active:  # never started: nothing to unwind
            self._queue.remove(record)
            self._finish(
                record,
                GoalStatus.CANCELED,
                self._framework_result(record, f"{reason} before it started"),
            )
            return
        self._call_cancel(record, reason)

    def _call_cancel(self, record: GoalRecord, reason: str) -> None:
        try:
            record.behaviour.cancel(self._now_s, reason)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "cancel", err)

    def _start_next(self) -> None:
        if self._active is not None or not self._queue:
            return
        record = self._active = self._queue.popleft()
        self._set_status(record, GoalStatus.EXECUTING)
        try:
            record.behaviour.start(record.goal, self._now_s)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "start", err)

    def _step_active(self) -> None:
        record = self._active
        if record is None:
            return
        try:
            step = record.behaviour.step(self._now_s)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "step", err)
            return
        if self._step_error(record, step) is None:
            if step.feedback is not None:
                self._publish_feedback(record, step.feedback)
            if step.status is not None:
                self._conclude(record, step)
        if self._active is record and record.status == GoalStatus.CANCELING:
            elapsed = self._now_s - record.cancel_requested_s
            if elapsed >= record.server.max_unwind_s:
                self._abort(
                    record,
                    f"unwind timed out: {record.label} was still CANCELING {elapsed:g} s after "
                    f"the cancel ({record.cancel_reason}); max_unwind_s is "
                    f"{record.server.max_unwind_s:g} s",
                )

    def _step_error(self, record: GoalRecord, step: Any) -> str | None:
        """Abort the goal if ``step`` is malformed; return the message (None if fine)."""
        action_type = record.server.action_type
        message = None
        if not isinstance(step, StepResult):
            message = f"behaviour.step returned {step!r}; expected a StepResult"
        elif step.feedback is not None and not isinstance(step.feedback, action_type.feedback_type):
            message = (
                f"behaviour.step returned feedback {step.feedback!r}; expected a "
                f"{action_type.feedback_type.__name__}"
            )
        elif step.status is not None and step.status not in legal_next_statuses(record.status):
            legal = " or ".join(
                s.name for s in sorted(legal_next_statuses(record.status)) if s.is_terminal
            )
            message = (
                f"behaviour.step reported {step.status.name} while the goal was "
                f"{record.status.name}; a goal that is {record.status.name} can only end {legal}"
            )
        elif step.status is not None and not isinstance(step.result, action_type.result_type):
            message = (
                f"behaviour.step returned result {step.result!r}; expected a "
                f"{action_type.result_type.__name__}"
            )
        if message is not None:
            self._abort(record, message)
        return message

    def _conclude(self, record: GoalRecord, step: StepResult[Any, Any]) -> None:
        if step.status == GoalStatus.CANCELED and record.preempted_by is not None:
            self._abort(record, record.preempted_by)
        else:
            self._finish(record, step.status, step.result)

    def _publish_feedback(self, record: GoalRecord, feedback: Any) -> None:
        self._log(record.goal_id, "feedback", repr(feedback))
        callback = record.feedback_callback
        if callback is None:
            return
        try:
            callback(FeedbackMessage(record.goal_id, feedback))
        except Exception as err:
            logger.exception("feedback callback of %s raised", record.label)
            self._log(
                record.goal_id,
                "callback_error",
                f"feedback callback raised {type(err).__name__}: {err}",
            )

    def _abort_on_exception(self, record: GoalRecord, method: str, err: Exception) -> None:
        logger.exception("behaviour.%s of %s raised", method, record.label)
        self._abort(record, f"behaviour.{method} raised {type(err).__name__}: {err}")

    def _abort(self, record: GoalRecord, message: str) -> None:
        self._finish(record, GoalStatus.ABORTED, self._framework_result(record, message))

    def _framework_result(self, record: GoalRecord, message: str) -> Any:
        result_type = record.server.action_type.result_type
        try:
            result = record.behaviour.abort_result(message)
            if not isinstance(result, result_type):
                raise ConfigurationError(
                    f"abort_result returned {result!r}; expected a {result_type.__name__}"
                )
        except Exception:
            logger.exception("behaviour.abort_result of %s failed", record.label)
            result = record.server.action_type.failure_result(message)
        return result

    def _finish(self, record: GoalRecord, status: GoalStatus, result: Any) -> None:
        self._set_status(record, status, repr(result))
        if self._active is record:
            self._active = None
        wrapped = WrappedResult(record.goal_id, status, result)
        _resolve(record.result_future, wrapped)

    def _reject(self, record: GoalRecord, rejection: Rejection) -> None:
        record.rejection = rejection
        self._log(record.goal_id, "rejected", f"code {rejection.code}: {rejection.message}")
        _resolve(record.handle_future, record.handle)

    def _set_status(self, record: GoalRecord, status: GoalStatus, detail: str = "") -> None:
        check_transition(record.status, status)
        record.status = status
        self._log(record.goal_id, status.name.lower(), detail)

    def _log(self, goal_id: str, event: str, detail: str) -> None:
        with self._events_lock:
            self._events.append(Event(self._now_s, goal_id, event, detail))


def _resolve(future: Future[Any], value: Any) -> None:
    """Set a future's result; done callbacks run here (their errors are logged by Future)."""
    try:
        future.set_result(value)
    except InvalidStateError:  # the client cancelled its future: nobody waits for it
        logger.debug("future %r was cancelled by its holder; dropping %r", future, value)
