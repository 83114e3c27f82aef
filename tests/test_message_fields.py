"""Tests of filling messages from mappings (what YAML and JSON goals become)."""

from __future__ import annotations

import pytest
import yaml

from actions import (
    Duration,
    FollowJointTrajectoryGoal,
    HighFiveGoal,
    JointTolerance,
    JointTrajectory,
    JointTrajectoryPoint,
)
from actions.errors import UnknownFieldError
from actions.message_fields import set_message_fields
from wbc.core.errors import ConfigurationError


def fill(cls: type, text: str) -> object:
    return set_message_fields(cls(), yaml.safe_load(text))


def test_flat_and_nested_goals_as_ros2_action_send_goal_takes_them() -> None:
    assert fill(HighFiveGoal, "{target_height: 0.4, hold_seconds: 2}") == HighFiveGoal(0.4, 2)
    goal = fill(FollowJointTrajectoryGoal, (
        "{trajectory: {joint_names: [FR_calf_joint], points: [{positions: [-1.9], "
        "time_from_start: {sec: 1, nanosec: 0}}, {positions: [-1.6], time_from_start: 2.5}]}, "
        "goal_tolerance: [{name: FR_calf_joint, position: 0.05}], goal_time_tolerance: 0.5}"))
    assert goal.validated_copy() == FollowJointTrajectoryGoal(
        trajectory=JointTrajectory(joint_names=["FR_calf_joint"], points=[
            JointTrajectoryPoint(positions=[-1.9], time_from_start=Duration(sec=1)),
            JointTrajectoryPoint(positions=[-1.6], time_from_start=2.5)]),
        goal_tolerance=[JointTolerance(name="FR_calf_joint", position=0.05)],
        goal_time_tolerance=0.5)


def test_fields_not_named_keep_their_values() -> None:
    goal = HighFiveGoal(target_height=0.3, hold_seconds=4)
    assert set_message_fields(goal, {"hold_seconds": 1}) is goal
    assert goal == HighFiveGoal(target_height=0.3, hold_seconds=1)


@pytest.mark.parametrize(("cls", "text", "error", "message"), [
    (HighFiveGoal, "{target_hieght: 0.4}", UnknownFieldError,
     "HighFiveGoal has no field 'target_hieght'; its fields: target_height, hold_seconds"),
    (FollowJointTrajectoryGoal, "{trajectory: {points: [{}, {time: 1}]}}", UnknownFieldError,
     ("FollowJointTrajectoryGoal.trajectory.points[1] (JointTrajectoryPoint) has no field "
      "'time'; its fields: positions, velocities, accelerations, effort, time_from_start")),
    (HighFiveGoal, "[0.4, 2]", ConfigurationError,
     ("HighFiveGoal must be a mapping of field names to values (e.g. {target_height: ...}); "
      "received [0.4, 2] (type list)")),
    (HighFiveGoal, "{1: 2}", UnknownFieldError,
     "HighFiveGoal has no field 1; its fields: target_height, hold_seconds"),
])
def test_unknown_fields_and_non_mappings_name_the_path(
    cls: type, text: str, error: type, message: str
) -> None:
    with pytest.raises(error) as info:
        fill(cls, text)
    assert str(info.value) == message


def test_types_are_checked_with_the_whole_path_when_validated() -> None:
    goal = fill(FollowJointTrajectoryGoal,
                "{trajectory: {points: [{positions: [1.0]}, {positions: [x]}]}}")
    with pytest.raises(ConfigurationError) as info:
        goal.validated_copy()
    assert str(info.value) == (
        "FollowJointTrajectoryGoal.trajectory.points[1].positions[0] must be a real number; "
        "received 'x' (type str)")
    goal = fill(FollowJointTrajectoryGoal, "{goal_time_tolerance: {sec: 1.5}}")
    with pytest.raises(ConfigurationError) as info:
        goal.validated_copy()
    assert str(info.value) == (
        "FollowJointTrajectoryGoal.goal_time_tolerance.sec must be an integer; received 1.5 "
        "(type float)")
