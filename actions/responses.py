"""Small reply types of the action protocol: goal and cancel responses, feedback, wrapped results.

ROS 2 analogues: ``rclpy.action.GoalResponse`` (here with a :class:`Rejection` that carries a
code and a message, where ROS 2 only says "rejected"), ``action_msgs/srv/CancelGoal``'s return
codes, the feedback message handed to a client's feedback callback, and the response of
``get_result_async`` (status + result).
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from enum import Enum, IntEnum
from typing import Generic, TypeVar

from actions.goal_status import GoalStatus
from wbc.core.errors import ConfigurationError

#: The action's feedback and result classes (``HighFiveFeedback``, ``HighFiveResult``).
FeedbackT = TypeVar("FeedbackT")
ResultT = TypeVar("ResultT")


class GoalResponse(Enum):
    """What a goal (or cancel) callback decides; a :class:`Rejection` explains a refusal."""

    ACCEPT = "accept"
    REJECT = "reject"


class RejectionCode(IntEnum):
    """Rejection codes the framework itself uses. Action-specific codes may be any other int
    (e.g. ``FollowJointTrajectoryResult.INVALID_JOINTS``, -2)."""

    REJECTED = 1
    """The goal callback returned a bare ``GoalResponse.REJECT``."""
    CALLBACK_ERROR = 2
    """The goal callback or the behaviour factory raised, or the callback returned nonsense."""
    BUSY = 3
    """The robot is running another goal and the busy policy is ``REJECT``."""
    SHUT_DOWN = 4
    """The runner has been shut down."""


@dataclass(frozen=True)
class Rejection:
    """Why a goal was rejected.

    Attributes:
        code: A :class:`RejectionCode` or an action-specific integer code.
        message: A readable reason, e.g. which field was invalid and what is valid.
    """

    code: int
    message: str

    def __post_init__(self) -> None:
        if not isinstance(self.code, numbers.Integral) or isinstance(self.code, bool):
            raise ConfigurationError(
                f"Rejection.code must be an int; received {self.code!r} "
                f"(type {type(self.code).__name__})"
            )
        if not isinstance(self.message, str) or not self.message:
            raise ConfigurationError(
                f"Rejection.message must be a non-empty str saying why; received {self.message!r}"
            )


class CancelReturnCode(IntEnum):
    """Return codes of a cancel request, numbered as ``action_msgs/srv/CancelGoal``."""

    ERROR_NONE = 0
    """The cancel request was accepted: the goal is (or already was) CANCELING."""
    ERROR_REJECTED = 1
    """The server's cancel callback refused."""
    ERROR_UNKNOWN_GOAL_ID = 2
    """No such goal: it was rejected, so it never existed on the server."""
    ERROR_GOAL_TERMINATED = 3
    """The goal had already ended."""


@dataclass(frozen=True)
class CancelResponse:
    """The reply to a cancel request.

    Attributes:
        goal_id: The goal the request was about.
        return_code: The outcome.
        message: A readable explanation (the refusal reason, the goal's final status, ...).
    """

    goal_id: str
    return_code: CancelReturnCode
    message: str

    @property
    def accepted(self) -> bool:
        """Whether the goal is now canceling."""
        return self.return_code == CancelReturnCode.ERROR_NONE


@dataclass(frozen=True)
class FeedbackMessage(Generic[FeedbackT]):
    """What a client's feedback callback receives (as in rclpy: ``msg.feedback``).

    Attributes:
        goal_id: The goal that produced the feedback.
        feedback: The action's feedback message.
    """

    goal_id: str
    feedback: FeedbackT


@dataclass(frozen=True)
class WrappedResult(Generic[ResultT]):
    """A finished goal: its terminal status and the action's result message.

    Attributes:
        goal_id: The goal.
        status: ``SUCCEEDED``, ``CANCELED`` or ``ABORTED``.
        result: The action's result message (e.g. ``HighFiveResult``).
    """

    goal_id: str
    status: GoalStatus
    result: ResultT
