"""Errors raised by the action machinery, all in the library's :class:`~wbc.core.errors.WbcError` family."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from wbc.core.errors import ConfigurationError, WbcError

if TYPE_CHECKING:
    from concurrent.futures import Future

    from actions.client_goal_handle import ClientGoalHandle
    from actions.responses import Rejection


class UnknownFieldError(ConfigurationError, AttributeError):
    """A message has no field of that name (a misspelt field); the message lists its fields.

    An ``AttributeError`` too, as setting an unknown attribute on a ROS 2 message is.
    """


class IllegalTransitionError(WbcError):
    """A goal status change that the action state machine does not allow."""


class ActionUsageError(WbcError, RuntimeError):
    """An action API was called where it cannot work, e.g. a blocking wait inside a tick callback."""


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


class ActionTimeoutError(WbcError, TimeoutError):
    """A blocking action call did not finish in time. The goal is NOT cancelled.

    Attributes:
        goal_handle: The handle of the accepted goal, or ``None`` when the goal request itself
            had not been processed yet (then use :attr:`goal_handle_future`).
        goal_handle_future: Resolves to the goal's handle once a tick processes the request.
    """

    def __init__(
        self,
        message: str,
        *,
        goal_handle: ClientGoalHandle | None = None,
        goal_handle_future: Future[Any] | None = None,
    ) -> None:
        super().__init__(message)
        self.goal_handle = goal_handle
        self.goal_handle_future = goal_handle_future


class RunnerStalledError(ActionTimeoutError):
    """Nothing ticks the runner: no thread calls ``tick`` and no spin hook can drive it."""
