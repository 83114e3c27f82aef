"""``control_msgs``: the FollowJointTrajectory action and the joint tolerances its goal carries.

The messages are declared here for type checkers and checked at import against
``actions/interfaces/FollowJointTrajectory.action``, which defines them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

from actions.action_type import INTERFACES_DIR, ActionType
from actions.messages import Duration, Message
from actions.ros_interfaces.std_msgs import Header
from actions.ros_interfaces.trajectory_msgs import (
    JointTrajectory,
    JointTrajectoryPoint,
    MultiDOFJointTrajectory,
)

#: The ROS 2 package of FollowJointTrajectory.
CONTROL_MSGS_PACKAGE = "control_msgs"


@dataclass(slots=True)
class JointTolerance(Message):
    """``control_msgs/JointTolerance``: 0 means "server default", -1 means "no limit".

    Attributes:
        name: Joint name.
        position: Position tolerance [rad].
        velocity: Velocity tolerance [rad/s].
        acceleration: Acceleration tolerance [rad/s^2].
    """

    name: str = ""
    position: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0


@dataclass(slots=True)
class JointComponentTolerance(Message):
    """``control_msgs/JointComponentTolerance``: a tolerance on one component of a multi-DOF
    joint."""

    X_AXIS: ClassVar[int] = 1
    Y_AXIS: ClassVar[int] = 2
    Z_AXIS: ClassVar[int] = 3
    TRANSLATION: ClassVar[int] = 4
    ROTATION: ClassVar[int] = 5

    joint_name: str = ""
    component: int = 0
    position: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0


@dataclass(slots=True)
class FollowJointTrajectoryGoal(Message):
    """Goal of ``control_msgs/action/FollowJointTrajectory``.

    Attributes:
        trajectory: The joint trajectory to follow.
        multi_dof_trajectory: Multi-DOF part; a server without multi-DOF support rejects a
            non-empty one.
        path_tolerance: Per-joint tolerances checked during execution.
        component_path_tolerance: Per-component tolerances of multi-DOF joints (path).
        goal_tolerance: Per-joint tolerances checked at the end.
        component_goal_tolerance: Per-component tolerances of multi-DOF joints (goal).
        goal_time_tolerance: How long after the last point's time the goal tolerance may
            still be reached (a Duration or seconds).
    """

    trajectory: JointTrajectory = field(default_factory=JointTrajectory)
    multi_dof_trajectory: MultiDOFJointTrajectory = field(default_factory=MultiDOFJointTrajectory)
    path_tolerance: list[JointTolerance] = field(default_factory=list)
    component_path_tolerance: list[JointComponentTolerance] = field(default_factory=list)
    goal_tolerance: list[JointTolerance] = field(default_factory=list)
    component_goal_tolerance: list[JointComponentTolerance] = field(default_factory=list)
    goal_time_tolerance: Duration = field(default_factory=Duration)


@dataclass(slots=True)
class FollowJointTrajectoryResult(Message):
    """Result of ``FollowJointTrajectory``: an error code (0 on success) and a readable reason."""

    SUCCESSFUL: ClassVar[int] = 0
    INVALID_GOAL: ClassVar[int] = -1
    INVALID_JOINTS: ClassVar[int] = -2
    OLD_HEADER_TIMESTAMP: ClassVar[int] = -3
    PATH_TOLERANCE_VIOLATED: ClassVar[int] = -4
    GOAL_TOLERANCE_VIOLATED: ClassVar[int] = -5

    error_code: int = 0
    error_string: str = ""


@dataclass(slots=True)
class FollowJointTrajectoryFeedback(Message):
    """Feedback of ``FollowJointTrajectory``: desired, actual and error points per joint."""

    header: Header = field(default_factory=Header)
    joint_names: list[str] = field(default_factory=list)
    desired: JointTrajectoryPoint = field(default_factory=JointTrajectoryPoint)
    actual: JointTrajectoryPoint = field(default_factory=JointTrajectoryPoint)
    error: JointTrajectoryPoint = field(default_factory=JointTrajectoryPoint)


def _failure(message: str) -> FollowJointTrajectoryResult:
    # FollowJointTrajectory has no code for "ended by the framework"; INVALID_GOAL is the
    # closest and the error string says what happened.
    return FollowJointTrajectoryResult(
        error_code=FollowJointTrajectoryResult.INVALID_GOAL, error_string=message)


FOLLOW_JOINT_TRAJECTORY = ActionType.from_file(
    INTERFACES_DIR / "FollowJointTrajectory.action",
    package=CONTROL_MSGS_PACKAGE,
    goal_type=FollowJointTrajectoryGoal,
    result_type=FollowJointTrajectoryResult,
    feedback_type=FollowJointTrajectoryFeedback,
    failure_result=_failure,
)
