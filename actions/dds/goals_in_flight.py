"""A DDS client's goals in flight, and what each reply of the server does to them.

:class:`GoalsInFlight` is the client side's book: the goals sent and not yet ended, the cancel
requests not yet answered, and the handlers of the server's replies (goal response, cancel
response, feedback, status, result), which update the framework's
:class:`~actions.goal_record.GoalRecord` behind each
:class:`~actions.client_goal_handle.ClientGoalHandle` and resolve its futures. Replies come on
several topics, so they may arrive out of order: a status only ever moves a goal forward, a
result implies the goal was accepted, and feedback after a goal's result is dropped.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any

from actions.action_type import ActionType
from actions.client_goal_handle import ClientGoalHandle
from actions.dds.payload_codec import decode_message
from actions.goal_lifecycle import resolve
from actions.goal_record import GoalRecord
from actions.goal_status import GoalStatus
from actions.responses import (
    CancelResponse,
    CancelReturnCode,
    FeedbackMessage,
    Rejection,
    WrappedResult,
)
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.action_messages import (
    CancelGoalResponse,
    GoalFeedback,
    GoalResult,
    GoalStatusUpdate,
    SendGoalResponse,
)

logger = logging.getLogger(__name__)


@dataclass(eq=False)
class SentGoal:
    """A goal sent and not yet ended: its record, its handle and the handle's future."""

    record: GoalRecord
    handle: ClientGoalHandle
    handle_future: Future[ClientGoalHandle]


class GoalsInFlight:
    """The goals and cancel requests of one client awaiting the server. Thread-safe.

    Args:
        client_id: The client's id: replies to other clients are ignored.
        action_type: The action's interface, to decode feedback and results.
    """

    def __init__(self, client_id: str, action_type: ActionType) -> None:
        self._client_id = client_id
        self._action_type = action_type
        self._lock = threading.Lock()
        self._goals: dict[str, SentGoal] = {}
        self._cancels: dict[str, Future[CancelResponse]] = {}

    def add_goal(self, sent: SentGoal) -> None:
        """Track a goal about to be sent."""
        with self._lock:
            self._goals[sent.record.goal_id] = sent

    def add_cancel(self, request_id: str) -> Future[CancelResponse]:
        """Track a cancel request about to be sent; the future receives its answer."""
        future: Future[CancelResponse] = Future()
        with self._lock:
            self._cancels[request_id] = future
        return future

    def forget(self, *, goal_id: str | None = None, request_id: str | None = None) -> None:
        """Stop tracking a goal or cancel request that could not be sent."""
        with self._lock:
            self._goals.pop(goal_id or "", None)
            self._cancels.pop(request_id or "", None)

    def __len__(self) -> int:
        """How many goals are in flight."""
        return len(self._goals)

    def on_goal_response(self, response: SendGoalResponse) -> None:
        """Accepted: the handle's future resolves. Rejected: with the reason, and untracked."""
        if response.client_id != self._client_id:
            return
        sent = self._sent(response.goal_id, pop=not response.accepted)
        if sent is None or sent.handle_future.done():
            return
        if response.accepted:
            advance(sent.record, GoalStatus.ACCEPTED)
        else:
            sent.record.rejection = Rejection(response.rejection_code,
                                              response.message or "rejected (no reason given)")
        resolve(sent.handle_future, sent.handle)

    def on_cancel_response(self, response: CancelGoalResponse) -> None:
        """The cancel request's future resolves with the server's answer."""
        if response.client_id != self._client_id:
            return
        with self._lock:
            future = self._cancels.pop(response.request_id, None)
        if future is not None:
            resolve(future, CancelResponse(response.goal_id,
                                           CancelReturnCode(response.return_code),
                                           response.message))

    def on_feedback(self, sample: GoalFeedback) -> None:
        """The goal's feedback callback gets the decoded feedback; errors are logged."""
        sent = self._sent(sample.goal_id)
        if sent is None or sent.record.status.is_terminal:
            return  # not ours, or after the goal's result
        callback = sent.record.feedback_callback
        if callback is None:
            return
        try:
            feedback = decode_message(sample.feedback, self._action_type.feedback_type,
                                      what=f"feedback of goal {sample.goal_id}")
            callback(FeedbackMessage(sample.goal_id, feedback))
        except Exception:  # a callback's error must not stop the receiver
            logger.exception("feedback of goal %s failed", sample.goal_id)

    def on_status(self, sample: GoalStatusUpdate) -> None:
        """The goal's status moves forward to the one received."""
        sent = self._sent(sample.goal_id)
        if sent is not None:
            advance(sent.record, GoalStatus(sample.status))

    def on_result(self, sample: GoalResult) -> None:
        """The goal ends: its result future resolves (or fails, if the result is malformed)."""
        sent = self._sent(sample.goal_id, pop=True)
        if sent is None:
            return
        record, status = sent.record, GoalStatus(sample.status)
        record.status = status
        resolve(sent.handle_future, sent.handle)  # a result implies the goal was accepted
        try:
            result = decode_message(sample.result, self._action_type.result_type,
                                    what=f"result of goal {sample.goal_id}")
        except ConfigurationError as err:
            record.result_future.set_exception(err)
            return
        resolve(record.result_future, WrappedResult(sample.goal_id, status, result))

    def fail_all(self, error: Callable[[str], Exception]) -> None:
        """Fail every waiting future with ``error(what was waiting)`` and track nothing more."""
        with self._lock:
            goals, self._goals = self._goals, {}
            cancels, self._cancels = self._cancels, {}
        for goal_id, sent in goals.items():
            future: Future[Any] = (sent.record.result_future if sent.handle_future.done()
                                   else sent.handle_future)
            if not future.done():
                future.set_exception(error(f"goal {goal_id} was {sent.record.status.name}"))
        for future in cancels.values():
            if not future.done():
                future.set_exception(error("a cancel request was waiting for its answer"))

    def _sent(self, goal_id: str, *, pop: bool = False) -> SentGoal | None:
        with self._lock:
            return self._goals.pop(goal_id, None) if pop else self._goals.get(goal_id)


def advance(record: GoalRecord, status: GoalStatus) -> None:
    """Move a goal's status forward only (replies on several topics may arrive out of order)."""
    if not record.status.is_terminal and status > record.status:
        record.status = status
