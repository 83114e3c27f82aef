"""The GO2's own action interfaces (``go2_interfaces``): HighFive, Stand, Sit and Walk, and
every action type the library ships.

``actions/interfaces/*.action`` define them. The message classes are declared here so that
type checkers and editors see their fields (``HighFiveGoal(target_height=...)``), and each is
checked against its file at import: a field added to a file and not here fails the import,
naming the field. An ``.action`` file in that directory with no classes declared here is an
action type all the same (:data:`ACTION_TYPES`), its classes built from the file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

from actions.action_type import INTERFACES_DIR, ActionType, action_types_in
from actions.messages import Message
from actions.ros_interfaces.control_msgs import (
    FOLLOW_JOINT_TRAJECTORY,
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

#: The ROS 2 package of this library's own interfaces (HighFive, Stand, Sit).
GO2_INTERFACES_PACKAGE = "go2_interfaces"


@dataclass(slots=True)
class BehaviourResult(Message):
    """Result shared by HighFive, Stand and Sit: did it work, and a readable account."""

    success: bool = False
    message: str = ""


@dataclass(slots=True)
class PhaseFeedback(Message):
    """Feedback shared by HighFive, Stand and Sit.

    Attributes:
        phase: Name of the current phase (e.g. ``"raising"``).
        progress: 0.0 -> 1.0, never decreasing within one goal.
    """

    phase: str = ""
    progress: float = 0.0


@dataclass(slots=True)
class PoseGoal(Message):
    """Goal shared by Stand and Sit: move to a pose.

    Attributes:
        duration_s: Time to reach the pose [s].
    """

    duration_s: float = 2.0


@dataclass(slots=True)
class HighFiveGoal(Message):
    """Goal of HighFive: raise the front-right foot, hold it up, put it back down.

    Attributes:
        target_height: How high to raise the front leg [m].
        hold_seconds: How long to hold the raised position [s].
    """

    target_height: float = 0.0
    hold_seconds: int = 0


class HighFiveResult(BehaviourResult):
    """Result of HighFive."""

    __slots__ = ()


class HighFiveFeedback(PhaseFeedback):
    """Feedback of HighFive; phases e.g. standing, shifting, raising, ready, lowering, complete."""

    __slots__ = ()


class StandGoal(PoseGoal):
    """Goal of Stand: rise to the nominal standing pose in ``duration_s`` [s]."""

    __slots__ = ()


class StandResult(BehaviourResult):
    """Result of Stand."""

    __slots__ = ()


class StandFeedback(PhaseFeedback):
    """Feedback of Stand."""

    __slots__ = ()


class SitGoal(PoseGoal):
    """Goal of Sit: lower the body to the resting pose in ``duration_s`` [s]."""

    __slots__ = ()


class SitResult(BehaviourResult):
    """Result of Sit."""

    __slots__ = ()


class SitFeedback(PhaseFeedback):
    """Feedback of Sit."""

    __slots__ = ()


@dataclass(slots=True)
class WalkGoal(Message):
    """Goal of Walk: trot at a velocity (base heading frame) for a duration or a distance.

    Attributes:
        forward_mps: Forward velocity [m/s].
        lateral_mps: Leftward velocity [m/s].
        yaw_rate_radps: Turning rate, counter-clockwise seen from above [rad/s].
        duration_s: Walk this long [s], then stop; 0 when ``distance_m`` is given.
        distance_m: Walk this path length [m], then stop; 0 when ``duration_s`` is given.
    """

    forward_mps: float = 0.0
    lateral_mps: float = 0.0
    yaw_rate_radps: float = 0.0
    duration_s: float = 0.0
    distance_m: float = 0.0


@dataclass(slots=True)
class WalkResult(Message):
    """Result of Walk.

    Attributes:
        success: Whether the walk ended as asked, on four loaded feet.
        message: A readable account.
        distance_m: Path length travelled from the start to the stop [m].
    """

    success: bool = False
    message: str = ""
    distance_m: float = 0.0


@dataclass(slots=True)
class WalkFeedback(Message):
    """Feedback of Walk.

    Attributes:
        phase: ``standing``, ``starting``, ``walking``, ``stopping``, ``complete``,
            ``canceled`` or ``aborted``.
        progress: 0.0 -> 1.0 of the duration or the distance, never decreasing.
        gait_phase: Position in the gait cycle, 0.0 -> 1.0.
        distance_m: Path length travelled so far [m].
        forward_mps, lateral_mps: Measured velocity (the state estimate) [m/s].
        yaw_rate_radps: Measured turning rate [rad/s].
    """

    phase: str = ""
    progress: float = 0.0
    gait_phase: float = 0.0
    distance_m: float = 0.0
    forward_mps: float = 0.0
    lateral_mps: float = 0.0
    yaw_rate_radps: float = 0.0


_G = TypeVar("_G", bound=Message)
_R = TypeVar("_R", bound=Message)
_F = TypeVar("_F", bound=Message)


def _go2_action(
    name: str, goal_type: type[_G], result_type: type[_R], feedback_type: type[_F],
) -> ActionType[_G, _R, _F]:
    """An action of ``go2_interfaces`` whose declared classes are checked against its file."""
    return ActionType.from_file(
        INTERFACES_DIR / f"{name}.action", package=GO2_INTERFACES_PACKAGE, goal_type=goal_type,
        result_type=result_type, feedback_type=feedback_type)


HIGH_FIVE = _go2_action("HighFive", HighFiveGoal, HighFiveResult, HighFiveFeedback)
STAND = _go2_action("Stand", StandGoal, StandResult, StandFeedback)
SIT = _go2_action("Sit", SitGoal, SitResult, SitFeedback)
WALK = _go2_action("Walk", WalkGoal, WalkResult, WalkFeedback)

#: Every action type shipped with the library, by interface name: one per ``.action`` file
#: of :data:`~actions.action_type.INTERFACES_DIR` (those above, control_msgs'
#: FollowJointTrajectory, and any other file there, its classes built from the file).
ACTION_TYPES: dict[str, ActionType] = action_types_in(
    INTERFACES_DIR, package=GO2_INTERFACES_PACKAGE,
    known=(HIGH_FIVE, FOLLOW_JOINT_TRAJECTORY, STAND, SIT, WALK),
    types=(Header, Vector3, Quaternion, Transform, Twist, JointTrajectoryPoint, JointTrajectory,
           MultiDOFJointTrajectoryPoint, MultiDOFJointTrajectory, JointTolerance,
           JointComponentTolerance))
