"""The ROS 2 names and types of the GO2's actions (no rclpy here: the command line reads them
before it imports the node)."""

from __future__ import annotations

from actions.go2.go2_actions import (
    FOLLOW_JOINT_TRAJECTORY_ACTION,
    HIGH_FIVE_ACTION,
    SIT_ACTION,
    STAND_ACTION,
    WALK_ACTION,
)

#: The runner's action name -> its ROS 2 name, relative (the node's namespace applies);
#: FollowJointTrajectory under the name ros2_control's trajectory controller gives it.
ROS_ACTION_NAMES: dict[str, str] = {
    HIGH_FIVE_ACTION: "high_five",
    STAND_ACTION: "stand",
    SIT_ACTION: "sit",
    FOLLOW_JOINT_TRAJECTORY_ACTION: "joint_trajectory_controller/follow_joint_trajectory",
    WALK_ACTION: "walk",
}
#: The runner's action name -> ``(module, class)`` of its rosidl type.
ROS_ACTION_TYPES: dict[str, tuple[str, str]] = {
    HIGH_FIVE_ACTION: ("go2_interfaces.action", "HighFive"),
    STAND_ACTION: ("go2_interfaces.action", "Stand"),
    SIT_ACTION: ("go2_interfaces.action", "Sit"),
    WALK_ACTION: ("go2_interfaces.action", "Walk"),
    FOLLOW_JOINT_TRAJECTORY_ACTION: ("control_msgs.action", "FollowJointTrajectory"),
}
#: The node's default name.
DEFAULT_NODE_NAME = "go2_wbc"


def ros_action_type(local_name: str) -> type:
    """The rosidl action type of the runner's action ``local_name`` (imports it)."""
    import importlib

    module, name = ROS_ACTION_TYPES[local_name]
    return getattr(importlib.import_module(module), name)
