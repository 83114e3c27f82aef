"""Descriptors tying an action's name to its goal, result and feedback types.

The ROS 2 analogue is the generated action class (``control_msgs.action.FollowJointTrajectory``
with its ``Goal``, ``Result`` and ``Feedback``): ``FOLLOW_JOINT_TRAJECTORY.Goal(...)`` reads the
same.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from actions.messages import (
    BehaviourResult,
    FollowJointTrajectoryFeedback,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    HighFiveFeedback,
    HighFiveGoal,
    HighFiveResult,
    PhaseFeedback,
    SitFeedback,
    SitGoal,
    SitResult,
    StandFeedback,
    StandGoal,
    StandResult,
)
from wbc.errors import ConfigurationError

INTERFACES_DIR = Path(__file__).resolve().parent / "interfaces"


@dataclass(frozen=True)
class ActionType:
    """An action interface: its name and message types.

    Attributes:
        name: Interface name, also the ``.action`` file's stem (``"HighFive"``).
        goal_type: Class of the goal message.
        result_type: Class of the result message.
        feedback_type: Class of the feedback message.
        failure_result: Builds a failure result from a message. The runner uses it only when
            a behaviour's own ``abort_result`` raises or returns the wrong type, so that every
            goal still ends with a result of ``result_type``.
    """

    name: str
    goal_type: type
    result_type: type
    feedback_type: type
    failure_result: Callable[[str], Any]

    def __post_init__(self) -> None:
        for attribute in ("goal_type", "result_type", "feedback_type"):
            value = getattr(self, attribute)
            if not isinstance(value, type):
                raise ConfigurationError(
                    f"ActionType {self.name!r}: {attribute} must be a class; received {value!r}"
                )
        if not callable(self.failure_result):
            raise ConfigurationError(
                f"ActionType {self.name!r}: failure_result must be callable; "
                f"received {self.failure_result!r}"
            )

    @property
    def Goal(self) -> type:  # rclpy spelling: FollowJointTrajectory.Goal
        """The goal class, as in ``FOLLOW_JOINT_TRAJECTORY.Goal(trajectory=...)``."""
        return self.goal_type

    @property
    def Result(self) -> type:
        """The result class."""
        return self.result_type

    @property
    def Feedback(self) -> type:
        """The feedback class."""
        return self.feedback_type

    @property
    def interface_path(self) -> Path:
        """The shipped ``.action`` file that defines this interface."""
        return INTERFACES_DIR / f"{self.name}.action"


def _behaviour_action(
    name: str,
    goal_type: type,
    result_type: type[BehaviourResult],
    feedback_type: type[PhaseFeedback],
) -> ActionType:
    """An action with a success/message result and a phase/progress feedback."""
    return ActionType(
        name=name,
        goal_type=goal_type,
        result_type=result_type,
        feedback_type=feedback_type,
        failure_result=lambda message: result_type(success=False, message=message),
    )


HIGH_FIVE = _behaviour_action("HighFive", HighFiveGoal, HighFiveResult, HighFiveFeedback)
STAND = _behaviour_action("Stand", StandGoal, StandResult, StandFeedback)
SIT = _behaviour_action("Sit", SitGoal, SitResult, SitFeedback)
# FollowJointTrajectory has no code for "ended by the framework"; INVALID_GOAL is the closest
# and the error string says what happened.
FOLLOW_JOINT_TRAJECTORY = ActionType(
    name="FollowJointTrajectory",
    goal_type=FollowJointTrajectoryGoal,
    result_type=FollowJointTrajectoryResult,
    feedback_type=FollowJointTrajectoryFeedback,
    failure_result=lambda message: FollowJointTrajectoryResult(
        error_code=FollowJointTrajectoryResult.INVALID_GOAL, error_string=message
    ),
)

#: Every action type shipped with the library, by interface name.
ACTION_TYPES: dict[str, ActionType] = {
    action.name: action for action in (HIGH_FIVE, FOLLOW_JOINT_TRAJECTORY, STAND, SIT)
}
