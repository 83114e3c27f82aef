"""The .action files are the one schema: declared classes are checked against them, others built
from them, and a change to a file shows in both (actions/message_schema.py, ActionType.from_file).
"""

from __future__ import annotations

import dataclasses
import typing
from pathlib import Path

import pytest

from actions import (
    ACTION_TYPES,
    FOLLOW_JOINT_TRAJECTORY,
    HIGH_FIVE,
    STAND,
    ActionType,
    FollowJointTrajectoryGoal,
    HighFiveGoal,
    InterfaceMismatchError,
    JointTrajectory,
    JointTrajectoryPoint,
    UnknownFieldError,
)
from actions.action_definition import parse_action_text
from actions.action_type import INTERFACES_DIR, action_types_in
from actions.go2.go2_interfaces import GO2_INTERFACES_PACKAGE
from actions.message_schema import check_message_class, message_class
from actions.messages import Duration, Message
from wbc.core.errors import ConfigurationError


def edited(tmp_path: Path, action_type: ActionType, old: str, new: str) -> Path:
    """A copy of ``action_type``'s shipped file in ``tmp_path`` with ``old`` replaced by ``new``."""
    text = action_type.interface_path.read_text()
    assert old in text, old
    path = tmp_path / action_type.interface_path.name
    path.write_text(text.replace(old, new, 1))
    return path


def with_declared_classes(path: Path, action_type: ActionType) -> ActionType:
    """``path`` made into an action type with ``action_type``'s declared classes (checked)."""
    return ActionType.from_file(path, package=action_type.package, goal_type=action_type.Goal,
                                result_type=action_type.Result,
                                feedback_type=action_type.Feedback,
                                failure_result=action_type.failure_result)


def mismatch(tmp_path: Path, action_type: ActionType, old: str, new: str) -> str:
    """The error of checking ``action_type``'s classes against its file edited, with the
    temporary directory written as ``TMP``."""
    path = edited(tmp_path, action_type, old, new)
    with pytest.raises(InterfaceMismatchError) as info:
        with_declared_classes(path, action_type)
    return str(info.value).replace(str(tmp_path), "TMP")


# --- one source: a change to a file shows in the classes -----------------------------------


def test_a_field_added_to_a_file_is_missing_from_the_declared_class(tmp_path):
    added = "int32 hold_seconds\nfloat32 speed"
    assert mismatch(tmp_path, HIGH_FIVE, "int32 hold_seconds", added) == (
        "HighFiveGoal does not match TMP/HighFive.action (goal): field 'speed' (line 5: float32 "
        "speed) is missing from the class; the file's fields: target_height, hold_seconds, "
        "speed; the class's: target_height, hold_seconds")


def test_a_field_added_to_a_file_is_a_field_of_the_built_class(tmp_path):
    path = edited(tmp_path, HIGH_FIVE, "int32 hold_seconds", "int32 hold_seconds\nfloat32 speed")
    built = ActionType.from_file(path, package=GO2_INTERFACES_PACKAGE)
    assert built.Goal(target_height=0.3, speed=2).speed == 2.0
    assert repr(built.Goal()) == "HighFiveGoal(target_height=0.0, hold_seconds=0, speed=0.0)"


def test_a_field_removed_from_a_file_is_one_too_many_in_the_class(tmp_path):
    assert mismatch(tmp_path, HIGH_FIVE, "int32 hold_seconds      #", "# int32 hold_seconds") == (
        "HighFiveGoal does not match TMP/HighFive.action (goal): field 'hold_seconds' of the "
        "class is not in the file; the file's fields: target_height; the class's: "
        "target_height, hold_seconds")


def test_a_type_changed_in_a_file_names_the_field_the_declaration_and_the_file(tmp_path):
    assert mismatch(tmp_path, HIGH_FIVE, "int32 hold_seconds", "float32 hold_seconds") == (
        "HighFiveGoal does not match TMP/HighFive.action (goal): field 'hold_seconds' is "
        "declared int; the file says float32 hold_seconds (line 4), which is float")
    assert mismatch(tmp_path, HIGH_FIVE, "float32 target_height", "float32[] target_height") == (
        "HighFiveGoal does not match TMP/HighFive.action (goal): field 'target_height' is "
        "declared float; the file says float32[] target_height (line 3), which is a list of "
        "float")
    assert mismatch(tmp_path, FOLLOW_JOINT_TRAJECTORY, "JointTrajectory trajectory ",
                    "MultiDOFJointTrajectory trajectory ") == (
        "FollowJointTrajectoryGoal does not match TMP/FollowJointTrajectory.action (goal): "
        "field 'trajectory' is declared JointTrajectory; the file says MultiDOFJointTrajectory "
        "trajectory (line 5), which is the message MultiDOFJointTrajectory")


def test_a_default_changed_in_a_file_names_the_field_and_both_values(tmp_path):
    assert mismatch(tmp_path, STAND, "float64 duration_s 2.0", "float64 duration_s 3.0") == (
        "StandGoal does not match TMP/Stand.action (goal): field 'duration_s' defaults to 2.0; "
        "the file gives the default 3.0 (line 3: float64 duration_s 3.0)")
    assert mismatch(tmp_path, STAND, "float64 duration_s 2.0", "float64 duration_s") == (
        "StandGoal does not match TMP/Stand.action (goal): field 'duration_s' defaults to 2.0; "
        "the file gives no default, so 0.0 (line 3: float64 duration_s)")


def test_fields_in_another_order_and_renamed_ones_are_named(tmp_path):
    text = HIGH_FIVE.interface_path.read_text()
    swapped = text.replace("float32 target_height", "int32 hold_seconds_", 1).replace(
        "int32 hold_seconds ", "float32 target_height ", 1).replace("hold_seconds_", "hold_seconds")
    path = tmp_path / "HighFive.action"
    path.write_text(swapped)
    with pytest.raises(InterfaceMismatchError) as info:
        with_declared_classes(path, HIGH_FIVE)
    assert str(info.value).replace(str(tmp_path), "TMP") == (
        "HighFiveGoal does not match TMP/HighFive.action (goal): the fields are in another "
        "order; the file's fields: hold_seconds, target_height; the class's: target_height, "
        "hold_seconds")
    assert mismatch(tmp_path, HIGH_FIVE, "string phase ", "string stage ") == (
        "HighFiveFeedback does not match TMP/HighFive.action (feedback): field 'stage' (line "
        "11: string stage) is missing from the class; the file's fields: stage, progress; the "
        "class's: phase, progress")


def test_a_constant_changed_added_or_removed_in_a_file_is_named(tmp_path):
    assert mismatch(tmp_path, FOLLOW_JOINT_TRAJECTORY, "int32 INVALID_GOAL = -1",
                    "int32 INVALID_GOAL = -7") == (
        "FollowJointTrajectoryResult does not match TMP/FollowJointTrajectory.action (result): "
        "constant 'INVALID_GOAL' is -1 in the class; the file says -7 (line 16)")
    assert mismatch(tmp_path, FOLLOW_JOINT_TRAJECTORY, "int32 SUCCESSFUL = 0",
                    "int32 SUCCESSFUL = 0\nint32 LATE = -6") == (
        "FollowJointTrajectoryResult does not match TMP/FollowJointTrajectory.action (result): "
        "constant 'LATE' (line 16: int32 LATE=-6) is missing from the class")
    assert mismatch(tmp_path, FOLLOW_JOINT_TRAJECTORY, "int32 OLD_HEADER_TIMESTAMP = -3\n",
                    "") == (
        "FollowJointTrajectoryResult does not match TMP/FollowJointTrajectory.action (result): "
        "the class has constants not in the file: OLD_HEADER_TIMESTAMP")


def test_the_shipped_files_and_classes_agree_and_every_file_is_an_action_type():
    for action_type in ACTION_TYPES.values():
        assert with_declared_classes(action_type.interface_path, action_type) == action_type
    assert set(ACTION_TYPES) == {path.stem for path in INTERFACES_DIR.glob("*.action")}


def test_a_new_file_beside_the_shipped_ones_becomes_an_action_type(tmp_path):
    for path in INTERFACES_DIR.glob("*.action"):
        (tmp_path / path.name).write_text(path.read_text())
    (tmp_path / "Wave.action").write_text(
        "int32 waves\n---\nbool success\nstring message\n---\nJointTrajectoryPoint pose\n")
    found = action_types_in(tmp_path, package="go2_interfaces",
                            types=_nested(FollowJointTrajectoryGoal))
    assert sorted(found) == ["FollowJointTrajectory", "HighFive", "Sit", "Stand", "Walk", "Wave"]
    wave = found["Wave"]
    assert wave.type_name == "go2_interfaces/action/Wave"
    assert wave.Feedback().pose == JointTrajectoryPoint()
    assert found["FollowJointTrajectory"].package == "go2_interfaces"  # built: no class known
    with pytest.raises(ConfigurationError) as info:
        action_types_in(tmp_path, package="go2_interfaces", known=(HIGH_FIVE,))
    assert str(info.value) == (
        f"action type 'HighFive' is defined by {HIGH_FIVE.interface_path}, not by a file in "
        f"{tmp_path.resolve()}")


# --- a built class is a declared class, from the same file -----------------------------------


@pytest.mark.parametrize("name", sorted(ACTION_TYPES))
def test_classes_built_from_a_shipped_file_have_the_declared_fields_types_and_defaults(name):
    declared = ACTION_TYPES[name]
    built = ActionType.from_file(declared.interface_path, package=declared.package,
                                 types=(JointTrajectory, *_nested(FollowJointTrajectoryGoal)))
    for built_class, declared_class in zip((built.Goal, built.Result, built.Feedback),
                                           (declared.Goal, declared.Result, declared.Feedback),
                                           strict=True):
        assert built_class.__name__ == declared_class.__name__
        built_hints, declared_hints = typing.get_type_hints(built_class), typing.get_type_hints(
            declared_class)
        assert built_hints == declared_hints
        assert dataclasses.asdict(built_class()) == dataclasses.asdict(declared_class())
        check_message_class(built_class, parse_action_text(
            declared.interface_path.read_text())[_section(built_class)], source=name,
            section="built")


def test_a_built_class_checks_and_names_its_fields_as_a_declared_one_does():
    built = ActionType.from_file(HIGH_FIVE.interface_path, package=GO2_INTERFACES_PACKAGE)
    for goal_class in (built.Goal, HighFiveGoal):
        with pytest.raises(ConfigurationError) as info:
            goal_class(target_height="high")
        assert str(info.value) == (
            "HighFiveGoal.target_height must be a real number; received 'high' (type str)")
        goal = goal_class()
        with pytest.raises(UnknownFieldError) as unknown:
            goal.target_hieght = 0.4
        assert str(unknown.value) == (
            "HighFiveGoal has no field 'target_hieght'; its fields: target_height, hold_seconds")
        goal.hold_seconds = 1.5
        with pytest.raises(ConfigurationError, match=r"^HighFiveGoal.hold_seconds must be an "
                                                     r"integer; received 1.5 \(type float\)$"):
            goal.validated_copy()
    assert built.failure("stopped") == built.Result(success=False, message="stopped")


def test_constants_of_a_built_class_are_class_constants_not_fields():
    built = ActionType.from_file(FOLLOW_JOINT_TRAJECTORY.interface_path, package="control_msgs",
                                 types=(JointTrajectory, *_nested(FollowJointTrajectoryGoal)))
    assert built.Result.INVALID_GOAL == -1
    assert [field.name for field in dataclasses.fields(built.Result)] == [
        "error_code", "error_string"]
    with pytest.raises(UnknownFieldError, match="has no field 'SUCCESSFUL' .it is a constant."):
        built.Result().SUCCESSFUL = 1
    assert built.failure("ended") == built.Result(error_code=0, error_string="ended")


# --- the files' own errors -----------------------------------------------------------------


def test_a_field_of_an_unknown_type_names_the_file_line_field_and_the_known_types(tmp_path):
    path = tmp_path / "Wave.action"
    path.write_text("# a wave\nPose target\n---\n---\n")
    with pytest.raises(ConfigurationError) as info:
        ActionType.from_file(path, package="toy_interfaces", types=(JointTrajectoryPoint,))
    assert str(info.value) == (
        f"{path}:2: field 'target' has type 'Pose', which is neither a primitive type nor a "
        "message class given in types; known types: float32, float64, byte, char, int8, uint8, "
        "int16, uint16, int32, uint32, int64, uint64, bool, string, wstring, duration, time, "
        "builtin_interfaces/Duration, builtin_interfaces/Time, JointTrajectoryPoint")


@pytest.mark.parametrize(("line", "message"), [
    ("int32 waves 1.5", "the default '1.5' of field 'waves' is not a valid int32"),
    ("bool fast maybe", "the default 'maybe' of field 'fast' is not a valid bool"),
    ("float64[] times [1, 'a']",
     "the default \"[1, 'a']\" of field 'times' is not a valid float64[]"),
    ("duration period 1",
     ("field 'period' of type duration cannot have a default (only numbers, bool and strings "
      "can); received '1'")),
    ("string coerce",
     ("field 'coerce' has the name of a method of every message; reserved names: coerce, "
      "validated_copy")),
])
def test_an_invalid_default_or_field_name_names_the_file_line_and_field(tmp_path, line, message):
    path = tmp_path / "Wave.action"
    path.write_text(f"{line}\n---\n---\n")
    with pytest.raises(ConfigurationError) as info:
        ActionType.from_file(path, package="toy_interfaces")
    assert str(info.value) == f"{path}:1: {message}"


def test_defaults_of_every_kind_are_read_from_the_file(tmp_path):
    path = tmp_path / "Wave.action"
    path.write_text('float64[] times [1, 2.5]\nbool fast true\nstring name "left"\nint8 n -3\n'
                    "uint8[3] ids\n---\n---\n")
    goal = ActionType.from_file(path, package="toy_interfaces").Goal()
    assert (goal.times, goal.fast, goal.name, goal.n, goal.ids) == ([1.0, 2.5], True, "left",
                                                                     -3, [])
    assert goal.times is not type(goal)().times


@pytest.mark.parametrize(("file_name", "message"), [
    ("wave.action",
     ("an action file is named after its interface in CamelCase with the suffix .action "
      "(e.g. HighFive.action); received 'wave.action'")),
    ("Wave.msg",
     ("an action file is named after its interface in CamelCase with the suffix .action "
      "(e.g. HighFive.action); received 'Wave.msg'")),
])
def test_a_file_not_named_as_an_interface_is_refused(tmp_path, file_name, message):
    path = tmp_path / file_name
    path.write_text("---\n---\n")
    with pytest.raises(ConfigurationError) as info:
        ActionType.from_file(path, package="toy_interfaces")
    assert str(info.value) == f"{path}: {message}"


def test_a_missing_file_is_named(tmp_path):
    path = tmp_path / "Wave.action"
    with pytest.raises(ConfigurationError, match=r"Wave.action: cannot read the action file: "):
        ActionType.from_file(path, package="toy_interfaces")


def test_a_declared_class_that_is_not_a_message_dataclass_is_refused():
    definition = parse_action_text("int32 waves\n---\n---\n")[0]

    class Plain:
        waves: int = 0

    with pytest.raises(InterfaceMismatchError) as info:
        check_message_class(Plain, definition, source="Wave.action", section="goal")
    assert str(info.value) == (
        f"Plain does not match Wave.action (goal): expected a @dataclass(slots=True) subclass "
        f"of Message; received {Plain!r}")

    @dataclasses.dataclass(slots=True)
    class NoDefault(Message):
        waves: int

    with pytest.raises(InterfaceMismatchError) as info:
        check_message_class(NoDefault, definition, source="Wave.action", section="goal")
    assert str(info.value).startswith(
        "NoDefault does not match Wave.action (goal): the class cannot be built empty "
        "(TypeError: ")


def test_an_action_type_needs_a_way_to_fail_unless_its_result_is_a_message():
    with pytest.raises(ConfigurationError) as info:
        ActionType("Wave", int, dict, str, package="toy_interfaces")
    assert str(info.value) == (
        "ActionType 'Wave': failure_result must be given, since the result type dict is not "
        "a Message to fill by default")
    with pytest.raises(ConfigurationError) as info:
        ActionType("wave", int, dict, str, package="toy_interfaces", failure_result=dict)
    assert str(info.value) == (
        "ActionType name must be an interface name in CamelCase (letters and digits, e.g. "
        "'HighFive'); received 'wave'")
    toy = ActionType("Wave", int, dict, str, package="toy_interfaces",
                     failure_result=lambda message: {"error": message})
    assert toy.failure("x") == {"error": "x"} and toy.interface_path is None


def test_a_built_class_reads_its_duration_fields_as_seconds_too():
    definition = parse_action_text("duration period\ntime start\n---\n---\n")[0]
    built = message_class("WaveGoal", definition, source="Wave.action")
    assert built(period=1.5).period == Duration(sec=1, nanosec=500_000_000)
    assert built.__doc__ == "WaveGoal, built from Wave.action."


def _nested(cls: type) -> tuple[type, ...]:
    """The message classes ``cls``'s fields name, at any depth."""
    found: dict[str, type] = {}
    pending = [cls]
    while pending:
        for hint in typing.get_type_hints(pending.pop()).values():
            for candidate in (hint, *typing.get_args(hint)):
                if isinstance(candidate, type) and issubclass(candidate, Message) and (
                        candidate.__name__ not in found):
                    found[candidate.__name__] = candidate
                    pending.append(candidate)
    return tuple(found.values())


def _section(cls: type) -> int:
    """0, 1 or 2: the section of the file a class of that name comes from."""
    return next(i for i, suffix in enumerate(("Goal", "Result", "Feedback"))
                if cls.__name__.endswith(suffix))
