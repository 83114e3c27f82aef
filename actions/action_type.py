"""Descriptors tying an action's name to its goal, result and feedback types.

The ROS 2 analogue is the generated action class (``control_msgs.action.FollowJointTrajectory``
with its ``Goal``, ``Result`` and ``Feedback``): ``FOLLOW_JOINT_TRAJECTORY.Goal(...)`` reads the
same.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
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
from wbc.core.errors import ConfigurationError, UnknownNameError

INTERFACES_DIR = Path(__file__).resolve().parent / "interfaces"
#: The ROS 2 package of this library's own interfaces (HighFive, Stand, Sit).
GO2_INTERFACES_PACKAGE = "go2_interfaces"
#: A ROS 2 package name (REP 144): lower case letters, digits and underscores.
_PACKAGE_NAME = re.compile(r"[a-z][a-z0-9_]*$")


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
        package: The ROS 2 package that defines the interface (``"control_msgs"`` for
            FollowJointTrajectory); :attr:`type_name` is the full name.
    """

    name: str
    goal_type: type
    result_type: type
    feedback_type: type
    failure_result: Callable[[str], Any]
    package: str = GO2_INTERFACES_PACKAGE

    def __post_init__(self) -> None:
        if not isinstance(self.package, str) or not _PACKAGE_NAME.match(self.package):
            raise ConfigurationError(
                f"ActionType {self.name!r}: package must be a ROS 2 package name (lower case "
                f"letters, digits and underscores, e.g. {GO2_INTERFACES_PACKAGE!r}); received "
                f"{self.package!r}")
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

    @property
    def type_name(self) -> str:
        """The full name, as ``ros2 action list -t`` prints it: ``go2_interfaces/action/HighFive``."""
        return f"{self.package}/action/{self.name}"

    def is_named(self, text: str) -> bool:
        """Whether ``text`` names this interface in a form ROS 2 takes: ``HighFive``,
        ``go2_interfaces/HighFive`` or ``go2_interfaces/action/HighFive``."""
        return text in (self.name, f"{self.package}/{self.name}", self.type_name)


def action_type_named(text: str, types: Iterable[ActionType] | None = None) -> ActionType:
    """The action type ``text`` names: ``HighFive``, ``go2_interfaces/HighFive`` or
    ``go2_interfaces/action/HighFive`` (as ``ros2 action send_goal`` and ``ros2 interface
    show`` take them).

    Args:
        text: The name.
        types: The types to choose from (default: :data:`ACTION_TYPES`).

    Raises:
        UnknownNameError: No such type; the message lists the valid full names (and the
            right package when only the package is wrong).
    """
    candidates = sorted(ACTION_TYPES.values() if types is None else types,
                        key=lambda t: t.type_name)
    for action_type in candidates:
        if action_type.is_named(text):
            return action_type
    last = text.rsplit("/", 1)[-1]
    same_name = [t.type_name for t in candidates if t.name == last]
    hint = f" ({last} is {' or '.join(same_name)})" if same_name else ""
    if not candidates:
        raise UnknownNameError(f"unknown action type {text!r}; there are no action types")
    valid = ", ".join(t.type_name for t in candidates)
    raise UnknownNameError(f"unknown action type {text!r}{hint}; valid action types: {valid} "
                           f"(or the last part alone, e.g. {candidates[-1].name})")


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
    package="control_msgs",
)

#: Every action type shipped with the library, by interface name.
ACTION_TYPES: dict[str, ActionType] = {
    action.name: action for action in (HIGH_FIVE, FOLLOW_JOINT_TRAJECTORY, STAND, SIT)
}
