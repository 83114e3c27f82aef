"""The goals of one runner from request to end: accept or reject, queue, start, step, cancel, end.

:class:`GoalLifecycle` makes every status change of every goal, on the ticking thread, under
the rules of :mod:`actions.goal_status`; :class:`~actions.action_runner.ActionRunner` owns the
threads, the requests and the clock, and calls it on each tick.
"""

from __future__ import annotations

import logging
from collections import deque
from concurrent.futures import Future, InvalidStateError
from typing import TYPE_CHECKING, Any, NamedTuple

from actions.behaviour import _GOES_ON, StepResult
from actions.busy_policy import BusyPolicy
from actions.goal_record import GoalRecord
from actions.goal_status import GoalStatus, check_transition, legal_next_statuses
from actions.responses import (
    CancelResponse,
    CancelReturnCode,
    FeedbackMessage,
    Rejection,
    RejectionCode,
    WrappedResult,
)
from wbc.core.errors import ConfigurationError

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from actions.event_log import EventLog

logger = logging.getLogger(__name__)

CANCELED_BY_CLIENT = "canceled by client request"


class GoalRequest(NamedTuple):
    """A goal sent by a client, to be accepted or rejected on the next tick."""

    record: GoalRecord
    handle: ClientGoalHandle
    future: Future[ClientGoalHandle]


class CancelRequest(NamedTuple):
    """A client's request to cancel a goal, answered on the next tick."""

    record: GoalRecord
    future: Future[CancelResponse]


class GoalLifecycle:
    """The goals of one runner: the one running (``active``) and the accepted ones waiting.

    Args:
        busy_policy: What a goal that arrives while the robot is busy gets.
        events: The runner's event log; every status change is logged there.

    Attributes:
        now_s: Simulated time [s] of the tick being run (set by the runner).
        active: The goal EXECUTING or CANCELING, if any.
        queue: Accepted goals waiting to start, oldest first.
    """

    def __init__(self, busy_policy: BusyPolicy, events: EventLog) -> None:
        self.busy_policy = busy_policy
        self.now_s: float | None = None
        self.active: GoalRecord | None = None
        self.queue: deque[GoalRecord] = deque()
        self._events = events

    # --- requests ------------------------------------------------------------------------

    def process_goal(self, request: GoalRequest) -> None:
        """Accept (queue) or reject a goal: its server's goal callback, then the busy policy."""
        record = request.record
        server = record.server
        busy = self.active is not None or bool(self.queue)
        rejection = server.evaluate_goal(record.goal)
        if rejection is None and busy and self.busy_policy is BusyPolicy.REJECT:
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
            self.reject(request, rejection)
            return
        self._set_status(record, GoalStatus.ACCEPTED)
        if busy:
            self._preempt_for(record)
        self.queue.append(record)
        resolve(request.future, request.handle)

    def reject(self, request: GoalRequest, rejection: Rejection) -> None:
        """Reject a goal: its handle says why."""
        request.record.rejection = rejection
        self.log(request.record.goal_id, "rejected",
                 f"code {rejection.code}: {rejection.message}")
        resolve(request.future, request.handle)

    def shut_down_rejection(self) -> Rejection:
        """The rejection of a goal sent to a runner that is shut down."""
        return Rejection(
            RejectionCode.SHUT_DOWN,
            f"the action runner was shut down at t={self.now_s:g} s; it accepts no new goals",
        )

    def process_cancel(self, request: CancelRequest) -> None:
        """Answer a cancel request: the goal starts CANCELING, or the refusal says why."""
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
                self.log(record.goal_id, "cancel_refused", refusal)
                code, message = CancelReturnCode.ERROR_REJECTED, refusal
        resolve(request.future, CancelResponse(record.goal_id, code, message))

    def shut_down(self, requests: list[GoalRequest | CancelRequest], reason: str) -> None:
        """End every goal: pending requests rejected, the active goal canceled then aborted,
        the queued ones aborted; pending cancel requests are answered last."""
        for request in requests:
            if isinstance(request, GoalRequest):
                self.reject(request, self.shut_down_rejection())
        self.abort_all(reason)
        for request in requests:
            if isinstance(request, CancelRequest):
                self.process_cancel(request)

    def abort_all(self, reason: str) -> None:
        """End the active goal (its behaviour canceled first, so it can release the robot)
        and the queued ones ABORTED with ``reason``."""
        active = self.active
        if active is not None:
            if active.status == GoalStatus.EXECUTING:
                self._call_cancel(active, reason)
            if self.active is active:
                self._abort(active, f"{reason} while the goal was {active.status.name}")
        while self.queue:
            self._abort(self.queue.popleft(), f"{reason} before the goal started")

    def _busy_rejection(self) -> Rejection:
        running = self.active if self.active is not None else self.queue[0]
        return Rejection(
            RejectionCode.BUSY,
            f"robot busy: {running.label} is {running.status.name} and the busy policy is "
            "REJECT; cancel that goal or wait for it to end, or use BusyPolicy.PREEMPT",
        )

    def _preempt_for(self, record: GoalRecord) -> None:
        reason = f"preempted by {record.label}"
        while self.queue:
            self._abort(self.queue.popleft(), f"{reason} before it started")
        active = self.active
        if active is not None and active.status == GoalStatus.EXECUTING:
            active.preempted_by = reason
            self._begin_cancel(active, reason)

    # --- goal lifecycle ------------------------------------------------------------------

    def _begin_cancel(self, record: GoalRecord, reason: str) -> None:
        self._set_status(record, GoalStatus.CANCELING, reason)
        record.cancel_reason = reason
        record.cancel_requested_s = self.now_s
        if record is not self.active:  # never started: nothing to unwind
            self.queue.remove(record)
            self._finish(
                record,
                GoalStatus.CANCELED,
                self._framework_result(record, f"{reason} before it started"),
            )
            return
        self._call_cancel(record, reason)

    def _call_cancel(self, record: GoalRecord, reason: str) -> None:
        try:
            record.behaviour.cancel(self.now_s, reason)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "cancel", err)

    def start_next(self) -> None:
        """If the robot is idle, start the oldest accepted goal: EXECUTING, ``start``."""
        if self.active is not None or not self.queue:
            return
        record = self.active = self.queue.popleft()
        self._set_status(record, GoalStatus.EXECUTING)
        try:
            record.behaviour.start(record.goal, self.now_s)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "start", err)

    def step_active(self) -> None:
        """Step the active goal's behaviour: publish its feedback, finish it if it ended, and
        abort it if it is still CANCELING ``max_unwind_s`` after its cancel."""
        record = self.active
        if record is None:
            return
        try:
            step = record.behaviour.step(self.now_s)
        except Exception as err:  # noqa: BLE001 - behaviour errors must not escape the tick
            self._abort_on_exception(record, "step", err)
            return
        # Most ticks return the shared "goes on" result: nothing to check, publish or conclude.
        if step is not _GOES_ON and self._step_error(record, step) is None:
            if step.feedback is not None:
                self._publish_feedback(record, step.feedback)
            if step.status is not None:
                self._conclude(record, step)
        if self.active is record and record.status == GoalStatus.CANCELING:
            elapsed = self.now_s - record.cancel_requested_s
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
        self.log(record.goal_id, "feedback", repr(feedback))
        callback = record.feedback_callback
        if callback is None:
            return
        try:
            callback(FeedbackMessage(record.goal_id, feedback))
        except Exception as err:
            logger.exception("feedback callback of %s raised", record.label)
            self.log(
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
            result = record.server.action_type.failure(message)
        return result

    def _finish(self, record: GoalRecord, status: GoalStatus, result: Any) -> None:
        self._set_status(record, status, repr(result))
        if self.active is record:
            self.active = None
        wrapped = WrappedResult(record.goal_id, status, result)
        resolve(record.result_future, wrapped)

    def _set_status(self, record: GoalRecord, status: GoalStatus, detail: str = "") -> None:
        check_transition(record.status, status)
        record.status = status
        self.log(record.goal_id, status.name.lower(), detail)

    def log(self, goal_id: str, event: str, detail: str) -> None:
        """Add an event at the current tick's time."""
        self._events.append(self.now_s, goal_id, event, detail)


def resolve(future: Future[Any], value: Any) -> None:
    """Set a future's result; done callbacks run here (their errors are logged by Future)."""
    try:
        future.set_result(value)
    except InvalidStateError:  # the client cancelled its future: nobody waits for it
        logger.debug("future %r was cancelled by its holder; dropping %r", future, value)
