"""A client's handle on one goal it sent (ROS 2: ``rclpy.action.client.ClientGoalHandle``)."""

from __future__ import annotations

import copy
from concurrent.futures import Future
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

from actions.goal_status import GoalStatus
from wbc.core.errors import WbcError

if TYPE_CHECKING:
    from actions.goal_record import GoalRecord
    from actions.responses import CancelResponse, Rejection, WrappedResult


class GoalRejectedError(WbcError):
    """A goal was rejected, so it has no result.

    Attributes:
        goal_id: The rejected goal.
        action_name: The action it was sent to.
        rejection: Why the server refused it (code and message).
    """

    def __init__(self, goal_id: str, action_name: str, rejection: Rejection) -> None:
        super().__init__(
            f"goal {goal_id} ({action_name}) was rejected (code {rejection.code}): "
            f"{rejection.message}"
        )
        self.goal_id = goal_id
        self.action_name = action_name
        self.rejection = rejection


class CancelSubmitter(Protocol):
    """What a handle sends its cancel requests to: the goal's runner."""

    def submit_cancel(self, record: GoalRecord) -> Future[CancelResponse]:
        """Queue a cancel request for ``record``'s goal; the future holds the reply."""
        ...


#: The goal's and the result's classes (``HighFiveGoal``, ``HighFiveResult``).
GoalT = TypeVar("GoalT")
ResultT = TypeVar("ResultT")


class ClientGoalHandle(Generic[GoalT, ResultT]):
    """The client's view of a goal: id, acceptance, live status, result and cancellation.

    Obtained from the future returned by ``ActionClient.send_goal_async``. Thread-safe. The
    goal's result is stored on the handle (in the future of :meth:`get_result_async`), so it
    stays available for as long as the handle is held, however many goals follow.
    """

    def __init__(self, runner: CancelSubmitter, record: GoalRecord) -> None:
        self._runner = runner
        self._record = record

    @property
    def goal_id(self) -> str:
        """The goal's id, unique per runner, assigned in submission order (``"1"``, ...)."""
        return self._record.goal_id

    @property
    def action_name(self) -> str:
        """The action the goal was sent to."""
        return self._record.server.action_name

    @property
    def goal(self) -> GoalT:
        """A copy of the goal as the server received it (validated and normalised).

        A copy, so that changing it cannot change the goal the server is running.
        """
        goal: GoalT = copy.deepcopy(self._record.goal)
        return goal

    @property
    def accepted(self) -> bool:
        """Whether the server accepted the goal."""
        return self._record.rejection is None and self._record.status != GoalStatus.UNKNOWN

    @property
    def rejection(self) -> Rejection | None:
        """Code and message of the rejection, or ``None`` if accepted."""
        return self._record.rejection

    @property
    def status(self) -> GoalStatus:
        """The latest status (``UNKNOWN`` for a rejected goal)."""
        return self._record.status

    def get_result_async(self) -> Future[WrappedResult[ResultT]]:
        """A future resolved with status and result on the tick the goal ends.

        Every call returns the same future; once done it keeps the result.

        Raises:
            GoalRejectedError: The goal was rejected, so it has no result.
        """
        if self._record.rejection is not None:
            raise GoalRejectedError(self.goal_id, self.action_name, self._record.rejection)
        future: Future[WrappedResult[ResultT]] = self._record.result_future
        return future

    def cancel_goal_async(self) -> Future[CancelResponse]:
        """Ask to cancel the goal; the future resolves on the next tick.

        An accepted request moves the goal to CANCELING on that tick (before the reply);
        the goal's result future then resolves when its unwind is over.
        """
        return self._runner.submit_cancel(self._record)

    def __repr__(self) -> str:
        return (
            f"ClientGoalHandle(goal_id={self.goal_id!r}, action_name={self.action_name!r}, "
            f"status={self.status.name})"
        )
