"""Actions with ROS 2 semantics, without ROS: goals, feedback, cancellation, results; and the
robot loop they run in (:class:`RobotInterface`, :class:`ControlLoop`)."""

from typing import TYPE_CHECKING, Any

from actions.action_client import ActionClient, ActionTimeoutError, RunnerStalledError
from actions.action_definition import (
    ActionDefinition,
    ConstantSpec,
    FieldSpec,
    MessageDefinition,
    parse_action_file,
    parse_action_text,
    parse_message_text,
)
from actions.action_runner import ActionRunner
from actions.action_server import ActionServer
from actions.action_type import ActionType, action_type_named
from actions.behaviour import Behaviour, StepResult
from actions.busy_policy import BusyPolicy
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.errors import (
    ActionUsageError,
    IllegalTransitionError,
    InterfaceMismatchError,
    UnknownFieldError,
)
from actions.event_log import Event
from actions.go2.go2_interfaces import (
    ACTION_TYPES,
    HIGH_FIVE,
    SIT,
    STAND,
    WALK,
    HighFiveFeedback,
    HighFiveGoal,
    HighFiveResult,
    SitFeedback,
    SitGoal,
    SitResult,
    StandFeedback,
    StandGoal,
    StandResult,
    WalkFeedback,
    WalkGoal,
    WalkResult,
)
from actions.goal_status import (
    LEGAL_TRANSITIONS,
    TERMINAL_STATUSES,
    GoalStatus,
    check_transition,
    legal_next_statuses,
)
from actions.message_fields import set_message_fields
from actions.messages import Duration, Time, as_duration
from actions.responses import (
    CancelResponse,
    CancelReturnCode,
    FeedbackMessage,
    GoalResponse,
    Rejection,
    RejectionCode,
    WrappedResult,
)
from actions.ros_interfaces.control_msgs import (
    FOLLOW_JOINT_TRAJECTORY,
    FollowJointTrajectoryFeedback,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    JointComponentTolerance,
    JointTolerance,
)
from actions.ros_interfaces.geometry_msgs import Quaternion, Transform, Twist, Vector3
from actions.ros_interfaces.std_msgs import Header
from actions.ros_interfaces.trajectory_msgs import (
    JointTrajectory,
    JointTrajectoryPoint,
    MultiDOFJointTrajectory,
    MultiDOFJointTrajectoryPoint,
)

if TYPE_CHECKING:
    from actions.robot.control_loop import ControlLoop
    from actions.robot.robot_interface import MappedRobot, RobotInterface, TrueState, check_robot

#: The robot loop's names (:mod:`actions.robot`'s), imported on first use: the loop pulls in
#: the controller, which a process that only sends goals (``go2-wbc high-five --dds``) does
#: not need (~1.7 s).
_ROBOT_LOOP = ("ControlLoop", "MappedRobot", "RobotInterface", "TrueState", "check_robot")


def __getattr__(name: str) -> Any:
    if name in _ROBOT_LOOP:
        import importlib

        return getattr(importlib.import_module("actions.robot"), name)
    raise AttributeError(f"module 'actions' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_ROBOT_LOOP})


__all__ = [
    "ACTION_TYPES",
    "FOLLOW_JOINT_TRAJECTORY",
    "HIGH_FIVE",
    "LEGAL_TRANSITIONS",
    "SIT",
    "STAND",
    "TERMINAL_STATUSES",
    "WALK",
    "ActionClient",
    "ActionDefinition",
    "ActionRunner",
    "ActionServer",
    "ActionTimeoutError",
    "ActionType",
    "ActionUsageError",
    "Behaviour",
    "BusyPolicy",
    "CancelResponse",
    "CancelReturnCode",
    "ClientGoalHandle",
    "ConstantSpec",
    "ControlLoop",
    "Duration",
    "Event",
    "FeedbackMessage",
    "FieldSpec",
    "FollowJointTrajectoryFeedback",
    "FollowJointTrajectoryGoal",
    "FollowJointTrajectoryResult",
    "GoalRejectedError",
    "GoalResponse",
    "GoalStatus",
    "Header",
    "HighFiveFeedback",
    "HighFiveGoal",
    "HighFiveResult",
    "IllegalTransitionError",
    "InterfaceMismatchError",
    "JointComponentTolerance",
    "JointTolerance",
    "JointTrajectory",
    "JointTrajectoryPoint",
    "MappedRobot",
    "MessageDefinition",
    "MultiDOFJointTrajectory",
    "MultiDOFJointTrajectoryPoint",
    "Quaternion",
    "Rejection",
    "RejectionCode",
    "RobotInterface",
    "RunnerStalledError",
    "SitFeedback",
    "SitGoal",
    "SitResult",
    "StandFeedback",
    "StandGoal",
    "StandResult",
    "StepResult",
    "Time",
    "Transform",
    "TrueState",
    "Twist",
    "UnknownFieldError",
    "Vector3",
    "WalkFeedback",
    "WalkGoal",
    "WalkResult",
    "WrappedResult",
    "action_type_named",
    "as_duration",
    "check_robot",
    "check_transition",
    "legal_next_statuses",
    "parse_action_file",
    "parse_action_text",
    "parse_message_text",
    "set_message_fields",
]
