"""``trajectory_msgs``: joint trajectories and their points (FollowJointTrajectory's goal)."""

from __future__ import annotations

from dataclasses import dataclass, field

from actions.messages import Duration, Message
from actions.ros_interfaces.geometry_msgs import Transform, Twist
from actions.ros_interfaces.std_msgs import Header


@dataclass(slots=True)
class JointTrajectoryPoint(Message):
    """``trajectory_msgs/JointTrajectoryPoint``: one waypoint, values in ``joint_names`` order.

    Attributes:
        positions: Joint positions [rad].
        velocities: Joint velocities [rad/s]; empty if unspecified.
        accelerations: Joint accelerations [rad/s^2]; empty if unspecified.
        effort: Joint torques [N m]; empty if unspecified.
        time_from_start: When to reach the point, from the trajectory start (a Duration or
            seconds).
    """

    positions: list[float] = field(default_factory=list)
    velocities: list[float] = field(default_factory=list)
    accelerations: list[float] = field(default_factory=list)
    effort: list[float] = field(default_factory=list)
    time_from_start: Duration = field(default_factory=Duration)


@dataclass(slots=True)
class JointTrajectory(Message):
    """``trajectory_msgs/JointTrajectory``: named joints and the waypoints they follow."""

    header: Header = field(default_factory=Header)
    joint_names: list[str] = field(default_factory=list)
    points: list[JointTrajectoryPoint] = field(default_factory=list)


@dataclass(slots=True)
class MultiDOFJointTrajectoryPoint(Message):
    """``trajectory_msgs/MultiDOFJointTrajectoryPoint``: one waypoint of multi-DOF joints."""

    transforms: list[Transform] = field(default_factory=list)
    velocities: list[Twist] = field(default_factory=list)
    accelerations: list[Twist] = field(default_factory=list)
    time_from_start: Duration = field(default_factory=Duration)


@dataclass(slots=True)
class MultiDOFJointTrajectory(Message):
    """``trajectory_msgs/MultiDOFJointTrajectory``; leave it empty unless a server supports it."""

    header: Header = field(default_factory=Header)
    joint_names: list[str] = field(default_factory=list)
    points: list[MultiDOFJointTrajectoryPoint] = field(default_factory=list)
