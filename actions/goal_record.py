"""The runner's bookkeeping for one goal (internal; clients see it through ClientGoalHandle)."""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from actions.goal_status import GoalStatus

if TYPE_CHECKING:
    from actions.action_server import ActionServer
    from actions.behaviour import Behaviour
    from actions.responses import FeedbackMessage, Rejection, WrappedResult


@dataclass(eq=False)
class GoalRecord:
    """Everything the runner knows about one goal. Written only by the ticking thread.

    Attributes:
        goal_id: Deterministic id, ``"1"``, ``"2"``, ... in order of submission.
        server: The action server the goal was sent to.
        goal: The goal message.
        feedback_callback: The client's feedback callback, or ``None``.
        status: Latest status; a rejected goal stays ``UNKNOWN``.
        rejection: Why it was rejected, or ``None``.
        behaviour: The behaviour running it, made when the goal is accepted.
        cancel_reason: Why the goal is canceling, or ``None``.
        cancel_requested_s: Simulated time [s] the cancel was acknowledged.
        preempted_by: ``"preempted by goal <id> (<action>)"`` if a preemption cancelled it.
        result_future: Resolves to the :class:`WrappedResult` when the goal ends.
    """

    goal_id: str
    server: ActionServer
    goal: Any
    feedback_callback: Callable[[FeedbackMessage], None] | None
    status: GoalStatus = GoalStatus.UNKNOWN
    rejection: Rejection | None = None
    behaviour: Behaviour[Any, Any, Any] | None = None
    cancel_reason: str | None = None
    cancel_requested_s: float | None = None
    preempted_by: str | None = None
    result_future: Future[WrappedResult] = field(default_factory=Future)

    @property
    def label(self) -> str:
        """``"goal <id> (<action name>)"``, as used in messages."""
        return f"goal {self.goal_id} ({self.server.action_name})"
