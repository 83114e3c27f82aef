"""Tests of the message dataclasses: the shipped .action files, filling, checking; the parser."""

from __future__ import annotations

import dataclasses
import typing
from pathlib import Path

import numpy as np
import pytest

import actions as messages
from actions import (
    ACTION_TYPES,
    FOLLOW_JOINT_TRAJECTORY,
    HIGH_FIVE,
    Duration,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    Header,
    HighFiveGoal,
    JointTrajectory,
    JointTrajectoryPoint,
    StandGoal,
    Time,
    as_duration,
)
from actions.action_definition import (
    FieldSpec,
    MessageDefinition,
    parse_action_file,
    parse_action_text,
    parse_message_text,
)
from actions.action_type import INTERFACES_DIR
from actions.errors import UnknownFieldError
from wbc.core.errors import ConfigurationError

PRIMITIVES: dict[str, type] = {
    **dict.fromkeys(("float32", "float64"), float),
    **dict.fromkeys(
        ("byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"),
        int,
    ),
    "bool": bool,
    "string": str,
    "duration": Duration,
    "time": Time,
}

# The ROS 2 definitions of the nested types, for checking the nested dataclasses too.
NESTED_DEFINITIONS = {
    "Duration": "int32 sec\nuint32 nanosec",
    "Time": "int32 sec\nuint32 nanosec",
    "Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "Transform": "Vector3 translation\nQuaternion rotation",
    "Twist": "Vector3 linear\nVector3 angular",
    "JointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nJointTrajectoryPoint[] points"
    ),
    "JointTrajectoryPoint": (
        "float64[] positions\nfloat64[] velocities\nfloat64[] accelerations\n"
        "float64[] effort\nbuiltin_interfaces/Duration time_from_start"
    ),
    "MultiDOFJointTrajectory": (
        "std_msgs/Header header\nstring[] joint_names\nMultiDOFJointTrajectoryPoint[] points"
    ),
    "MultiDOFJointTrajectoryPoint": (
        "geometry_msgs/Transform[] transforms\ngeometry_msgs/Twist[] velocities\n"
        "geometry_msgs/Twist[] accelerations\nbuiltin_interfaces/Duration time_from_start"
    ),
    "JointTolerance": "string name\nfloat64 position\nfloat64 velocity\nfloat64 acceleration",
    "JointComponentTolerance": (
        "uint16 X_AXIS=1\nuint16 Y_AXIS=2\nuint16 Z_AXIS=3\nuint16 TRANSLATION=4\n"
        "uint16 ROTATION=5\nstring joint_name\nuint16 component\nfloat64 position\n"
        "float64 velocity\nfloat64 acceleration"
    ),
}

ACTION_FILES = sorted(INTERFACES_DIR.glob("*.action"))


def expected_type(spec: FieldSpec) -> typing.Any:
    element = PRIMITIVES.get(spec.type_name) or getattr(messages, spec.base_type)
    return list[element] if spec.is_array else element


def check_message(cls: type, definition: MessageDefinition, checked: set[str]) -> None:
    """Field names, order, types, defaults and constants of ``cls`` match ``definition``."""
    hints = typing.get_type_hints(cls)
    fields = dataclasses.fields(cls)
    assert [f.name for f in fields] == [spec.name for spec in definition.fields], cls
    for spec, field in zip(definition.fields, fields, strict=True):
        assert hints[field.name] == expected_type(spec), (cls, spec)
        if spec.default is not None:
            assert getattr(cls(), field.name) == expected_type(spec)(spec.default), (cls, spec)
    class_constants = {
        name: getattr(cls, name)
        for name, hint in hints.items()
        if typing.get_origin(hint) is typing.ClassVar
    }
    assert class_constants == {c.name: c.value for c in definition.constants}, cls
    for spec in definition.fields:
        nested = spec.base_type
        if spec.type_name not in PRIMITIVES and nested not in checked:
            checked.add(nested)
            check_message(
                getattr(messages, nested), parse_message_text(NESTED_DEFINITIONS[nested]), checked
            )


def test_every_shipped_action_has_an_action_type_and_back() -> None:
    assert {path.stem for path in ACTION_FILES} == set(ACTION_TYPES)
    assert {"HighFive", "FollowJointTrajectory", "Stand", "Sit", "Walk"} == set(ACTION_TYPES)
    for name, action_type in ACTION_TYPES.items():
        assert action_type.interface_path == INTERFACES_DIR / f"{name}.action"


@pytest.mark.parametrize("path", ACTION_FILES, ids=lambda path: path.stem)
def test_dataclasses_match_the_action_file(path: Path) -> None:
    action_type = ACTION_TYPES[path.stem]
    goal, result, feedback = parse_action_file(path)
    checked: set[str] = set()
    check_message(action_type.Goal, goal, checked)
    check_message(action_type.Result, result, checked)
    check_message(action_type.Feedback, feedback, checked)
    if path.stem == "FollowJointTrajectory":  # nested types were reached and checked too
        assert checked == set(NESTED_DEFINITIONS)


def test_follow_joint_trajectory_result_constants() -> None:
    _, result, _ = parse_action_file(FOLLOW_JOINT_TRAJECTORY.interface_path)
    assert [(c.name, c.value) for c in result.constants] == [
        ("SUCCESSFUL", 0),
        ("INVALID_GOAL", -1),
        ("INVALID_JOINTS", -2),
        ("OLD_HEADER_TIMESTAMP", -3),
        ("PATH_TOLERANCE_VIOLATED", -4),
        ("GOAL_TOLERANCE_VIOLATED", -5),
    ]
    assert FollowJointTrajectoryResult.GOAL_TOLERANCE_VIOLATED == -5
    assert HIGH_FIVE.interface_path.read_text().count("---") == 2


def test_high_five_fields_are_the_documented_ones() -> None:
    goal, result, feedback = parse_action_file(HIGH_FIVE.interface_path)
    assert [(f.type_name, f.name) for f in goal.fields] == [
        ("float32", "target_height"),
        ("int32", "hold_seconds"),
    ]
    assert [f.name for f in result.fields] == ["success", "message"]
    assert [f.name for f in feedback.fields] == ["phase", "progress"]


# --- Duration and Time ---------------------------------------------------------------------


def test_duration_seconds_round_trip() -> None:
    assert Duration(sec=1, nanosec=0).to_seconds() == 1.0
    assert Duration.from_seconds(2.5) == Duration(sec=2, nanosec=500_000_000)
    assert Duration.from_seconds(-0.25) == Duration(sec=-1, nanosec=750_000_000)
    assert Duration.from_seconds(-0.25).to_seconds() == -0.25
    assert Duration.from_seconds(1e-9) == Duration(sec=0, nanosec=1)
    assert Duration.from_seconds(0.9999999999) == Duration(sec=1, nanosec=0)  # rounds
    assert Duration(sec=1) < Duration(sec=1, nanosec=1)


def test_as_duration_accepts_seconds_or_a_duration() -> None:
    duration = Duration(sec=3)
    assert as_duration(duration) is duration
    assert as_duration(3) == duration
    assert as_duration(np.float64(0.5)) == Duration(nanosec=500_000_000)
    with pytest.raises(ConfigurationError) as info:
        as_duration("3 s", "time_from_start")
    assert str(info.value) == (
        "time_from_start must be a Duration or a finite number of seconds; "
        "received '3 s' (type str)"
    )
    with pytest.raises(ConfigurationError, match="finite number of seconds; received nan"):
        as_duration(float("nan"))


def test_duration_and_time_validation() -> None:
    with pytest.raises(ConfigurationError) as info:
        Duration(sec=1, nanosec=1_000_000_000)
    assert str(info.value) == (
        "Duration.nanosec must be in [0, 999999999]; received 1000000000 "
        "(put whole seconds in sec, or use Duration.from_seconds)"
    )
    with pytest.raises(ConfigurationError, match="Time must not be negative"):
        Time.from_seconds(-1.0)
    with pytest.raises(ConfigurationError, match=r"Duration.sec must be an integer"):
        Duration(sec=1.5)


# --- construction, normalisation, validation ---------------------------------------------


def test_point_with_duration_or_seconds_and_empty_list_defaults() -> None:
    point = JointTrajectoryPoint(positions=[0.1, 0.2], time_from_start=Duration(sec=3))
    assert point.velocities == [] and point.accelerations == [] and point.effort == []
    assert point == JointTrajectoryPoint(positions=(0.1, 0.2), time_from_start=3.0)
    assert JointTrajectoryPoint().positions is not JointTrajectoryPoint().positions


def test_numbers_and_arrays_are_normalised() -> None:
    point = JointTrajectoryPoint(positions=np.array([1, 2]), velocities=[np.float32(0.5)])
    assert point.positions == [1.0, 2.0]
    assert all(type(value) is float for value in point.positions + point.velocities)
    goal = HighFiveGoal(target_height=1, hold_seconds=np.int64(2))
    assert (goal.target_height, goal.hold_seconds) == (1.0, 2)
    assert type(goal.hold_seconds) is int
    assert StandGoal().duration_s == 2.0


@pytest.mark.parametrize(
    "build, message",
    [
        (
            lambda: HighFiveGoal(target_height="high"),
            "HighFiveGoal.target_height must be a real number; received 'high' (type str)",
        ),
        (
            lambda: HighFiveGoal(hold_seconds=1.5),
            "HighFiveGoal.hold_seconds must be an integer; received 1.5 (type float)",
        ),
        (
            lambda: HighFiveGoal(hold_seconds=True),
            "HighFiveGoal.hold_seconds must be an integer; received True (type bool)",
        ),
        (
            lambda: JointTrajectoryPoint(positions=[0.1, None]),
            (
                "JointTrajectoryPoint.positions[1] must be a real number; received None "
                "(type NoneType)"
            ),
        ),
        (
            lambda: JointTrajectoryPoint(positions="0.1"),
            (
                "JointTrajectoryPoint.positions must be a sequence (list, tuple or array); "
                "received '0.1' (type str)"
            ),
        ),
        (
            lambda: FollowJointTrajectoryGoal(trajectory=[1.0]),
            (
                "FollowJointTrajectoryGoal.trajectory must be a JointTrajectory; "
                "received [1.0] (type list)"
            ),
        ),
        (
            lambda: FollowJointTrajectoryResult(error_string=3),
            "FollowJointTrajectoryResult.error_string must be a str; received 3 (type int)",
        ),
    ],
)
def test_wrong_field_types_are_rejected_with_field_received_and_valid(
    build: typing.Callable[[], object], message: str
) -> None:
    with pytest.raises(ConfigurationError) as info:
        build()
    assert str(info.value) == message


# The keyword cases above, as (class, field, value, message): filled field by field, the same
# value gets the same message when the message is validated for sending.
FIELD_BY_FIELD = [
    (HighFiveGoal, "target_height", "high",
     "HighFiveGoal.target_height must be a real number; received 'high' (type str)"),
    (HighFiveGoal, "hold_seconds", 1.5,
     "HighFiveGoal.hold_seconds must be an integer; received 1.5 (type float)"),
    (HighFiveGoal, "hold_seconds", True,
     "HighFiveGoal.hold_seconds must be an integer; received True (type bool)"),
    (JointTrajectoryPoint, "positions", [0.1, None],
     "JointTrajectoryPoint.positions[1] must be a real number; received None (type NoneType)"),
    (JointTrajectoryPoint, "positions", "0.1",
     ("JointTrajectoryPoint.positions must be a sequence (list, tuple or array); received "
      "'0.1' (type str)")),
    (FollowJointTrajectoryGoal, "trajectory", [1.0],
     ("FollowJointTrajectoryGoal.trajectory must be a JointTrajectory; received [1.0] "
      "(type list)")),
    (FollowJointTrajectoryResult, "error_string", 3,
     "FollowJointTrajectoryResult.error_string must be a str; received 3 (type int)"),
    (Duration, "nanosec", 1_000_000_000,
     ("Duration.nanosec must be in [0, 999999999]; received 1000000000 (put whole seconds "
      "in sec, or use Duration.from_seconds)")),
]


@pytest.mark.parametrize(("cls", "name", "value", "message"), FIELD_BY_FIELD,
                         ids=[f"{case[0].__name__}.{case[1]}={case[2]!r}"
                              for case in FIELD_BY_FIELD])
def test_a_field_set_by_assignment_is_checked_when_validated_like_a_keyword(
    cls: type, name: str, value: object, message: str
) -> None:
    with pytest.raises(ConfigurationError) as built:
        cls(**{name: value})
    assert str(built.value) == message
    filled = cls()
    setattr(filled, name, value)  # not checked on the spot, as the message is being filled
    with pytest.raises(ConfigurationError) as sent:
        filled.validated_copy()
    assert str(sent.value) == message


def test_messages_are_built_empty_and_filled_field_by_field_nested_ones_included() -> None:
    goal = FollowJointTrajectoryGoal()
    assert goal.trajectory.joint_names == [] and goal.trajectory.points == []
    assert goal.goal_time_tolerance == Duration() and goal.trajectory.header.frame_id == ""
    goal.trajectory.joint_names = ["FR_calf_joint"]
    point = JointTrajectoryPoint()
    point.positions = [-1.9]
    point.time_from_start = Duration(sec=1)
    goal.trajectory.points.append(point)
    goal.goal_time_tolerance.sec = 1
    assert goal == FollowJointTrajectoryGoal(
        trajectory=JointTrajectory(
            joint_names=["FR_calf_joint"],
            points=[JointTrajectoryPoint(positions=[-1.9], time_from_start=1.0)],
        ),
        goal_time_tolerance=Duration(sec=1),
    )
    assert FollowJointTrajectoryGoal().trajectory is not FollowJointTrajectoryGoal().trajectory
    high_five = HighFiveGoal()
    high_five.target_height = 0.4
    high_five.hold_seconds = 2
    assert repr(high_five) == "HighFiveGoal(target_height=0.4, hold_seconds=2)"
    assert dataclasses.replace(high_five, hold_seconds=3) == HighFiveGoal(0.4, 3)


def test_a_misspelt_field_is_an_error_listing_the_fields() -> None:
    goal = HighFiveGoal()
    with pytest.raises(UnknownFieldError) as info:
        goal.target_hieght = 0.4  # type: ignore[attr-defined]
    assert str(info.value) == (
        "HighFiveGoal has no field 'target_hieght'; its fields: target_height, hold_seconds"
    )
    assert isinstance(info.value, AttributeError) and isinstance(info.value, ConfigurationError)
    with pytest.raises(UnknownFieldError, match="has no field 'SUCCESSFUL' .it is a constant."):
        FollowJointTrajectoryResult().SUCCESSFUL = 1  # type: ignore[misc]
    with pytest.raises(UnknownFieldError, match="StandResult has no field 'sucess'"):
        ACTION_TYPES["Stand"].Result().sucess = True  # subclasses have no __dict__ either


def test_validated_copy_is_deep_normalised_and_leaves_the_original_as_it_was() -> None:
    goal = FollowJointTrajectoryGoal()
    point = JointTrajectoryPoint()
    point.positions = (np.int64(1), 2)
    point.time_from_start = 1.5
    goal.trajectory.points.append(point)
    copy = goal.validated_copy()
    sent_point = copy.trajectory.points[0]
    assert sent_point.positions == [1.0, 2.0]
    assert all(type(x) is float for x in sent_point.positions)
    assert sent_point.time_from_start == Duration(sec=1, nanosec=500_000_000)
    assert point.positions == (1, 2) and point.time_from_start == 1.5  # untouched
    assert sent_point is not point and copy.trajectory is not goal.trajectory
    point.positions = [5.0]
    goal.trajectory.points.append(JointTrajectoryPoint())
    assert copy.trajectory.points == [JointTrajectoryPoint(positions=[1.0, 2.0],
                                                           time_from_start=1.5)]


def test_a_nested_error_names_the_path_from_the_message_checked() -> None:
    goal = FollowJointTrajectoryGoal()
    goal.trajectory.points.append(JointTrajectoryPoint(positions=[0.1]))
    goal.trajectory.points.append(JointTrajectoryPoint())
    goal.trajectory.points[1].positions.append("x")
    expected = "trajectory.points[1].positions[0] must be a real number; received 'x' (type str)"
    with pytest.raises(ConfigurationError) as sent:
        goal.validated_copy()
    assert str(sent.value) == f"FollowJointTrajectoryGoal.{expected}"
    with pytest.raises(ConfigurationError) as built:  # the same goal, built with keywords
        FollowJointTrajectoryGoal(trajectory=goal.trajectory)
    assert str(built.value) == f"FollowJointTrajectoryGoal.{expected}"
    goal.trajectory.points[1].positions = [0.2]
    goal.trajectory.header.stamp.sec = -1
    with pytest.raises(ConfigurationError) as stamp:
        goal.validated_copy()
    assert str(stamp.value) == (
        "FollowJointTrajectoryGoal.trajectory.header.stamp must not be negative; received "
        "sec=-1, nanosec=0"
    )


def test_duration_fields_accept_the_rclpy_style_duration_and_time() -> None:
    from actions.duration import Duration as RclpyDuration
    from actions.time import Time as RclpyTime

    point = JointTrajectoryPoint()
    point.time_from_start = RclpyDuration(seconds=1.25)
    header = Header(stamp=RclpyTime(seconds=2, nanoseconds=5))
    assert point.validated_copy().time_from_start == Duration(sec=1, nanosec=250_000_000)
    assert header.stamp == Time(sec=2, nanosec=5)
    with pytest.raises(ConfigurationError, match="Header.stamp must be a Time or a finite"):
        Header(stamp=RclpyDuration(seconds=1))


def test_results_of_different_actions_are_not_equal() -> None:
    stand = ACTION_TYPES["Stand"].Result(success=True, message="ok")
    sit = ACTION_TYPES["Sit"].Result(success=True, message="ok")
    assert stand != sit
    assert repr(stand) == "StandResult(success=True, message='ok')"


# --- parser ------------------------------------------------------------------------------


def test_parser_handles_comments_constants_defaults_and_arrays() -> None:
    goal, result, feedback = parse_action_text(
        "# header comment\n"
        "float64[3] xyz   # fixed size\n"
        "int32[<=4] ids\n"
        "string<=8 label \n"
        "float32 speed 0.5  # default\n"
        "\tbool\tflag\n"
        "---\n"
        "int8 SMALL=-3\n"
        'string GREETING = "hi # not a comment"\n'
        "bool YES=true\n"
        "---\n"
        "std_msgs/Header header\n"
    )
    assert goal.fields == (
        FieldSpec("float64", "xyz", True, 3, None),
        FieldSpec("int32", "ids", True, 4, None),
        FieldSpec("string", "label", False, None, None),
        FieldSpec("float32", "speed", False, None, "0.5"),
        FieldSpec("bool", "flag", False, None, None),
    )
    assert [(c.name, c.value) for c in result.constants] == [
        ("SMALL", -3),
        ("GREETING", "hi # not a comment"),
        ("YES", True),
    ]
    assert result.fields == ()
    assert feedback.fields[0].base_type == "Header"


def test_parser_errors_name_the_source_and_line() -> None:
    with pytest.raises(ConfigurationError) as info:
        parse_action_text("float64 x\n---\nbool ok\n", source="Bad.action")
    assert str(info.value) == (
        "Bad.action: an action definition needs 3 sections (goal, result, feedback) "
        "separated by '---' lines; found 2"
    )
    with pytest.raises(ConfigurationError) as info:
        parse_action_text("float64\n---\n---\n", source="Bad.action")
    assert str(info.value) == (
        "Bad.action:1: expected '<type> <name> [default]' or '<type> <NAME>=<value>'; "
        "received 'float64'"
    )
    with pytest.raises(ConfigurationError) as info:
        parse_action_text("---\nint32 CODE = x\n---\n", source="Bad.action")
    assert str(info.value) == "Bad.action:2: constant CODE = 'x' is not a valid int32"


def test_float_arrays_become_lists_of_python_floats():
    for array in (np.array([0.5, -1.25]), np.array([0.5, -1.25], dtype=np.float32),
                  np.array([[0.5, -1.25]])[0]):
        point = JointTrajectoryPoint(positions=array)
        assert point.positions == [0.5, -1.25]
        assert all(type(x) is float for x in point.positions)
    with pytest.raises(ConfigurationError, match=r"positions\[0\] must be a real number"):
        JointTrajectoryPoint(positions=np.array(["0.5", "x"]))  # not float arrays: checked
