"""go2-wbc send-goal, actions and interface end to end: output, exit codes, one-line errors."""

from __future__ import annotations

import contextlib
import io
import itertools

import pytest
import yaml

from actions.go2.go2_actions import GO2_ACTIONS
from actions.go2.go2_interfaces import ACTION_TYPES, HIGH_FIVE
from actions.go2.high_five_behaviour import INVALID_TARGET_HEIGHT
from sim.cli import EXIT_CODES_HELP, EXIT_REJECTED, EXIT_SUCCEEDED, EXIT_USAGE, main
from sim.control_loop import ControlLoop

HIGH_FIVE_PHASES = ["shifting", "unloading", "raising", "ready", "lowering", "reloading",
                    "shifting_back", "complete"]


def run(argv: list[str]) -> tuple[int, str]:
    """``main(argv)`` in this process; returns the exit code and what it printed."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue()


def usage_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Run ``argv``, expecting exit 2; returns the message (checked to be one line)."""
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    return lines[0]


def section(out: str, title: str) -> dict:
    """The YAML block printed under ``title`` (up to the next blank line)."""
    block = out.split(f"\n{title}:\n", 1)[1].split("\n\n", 1)[0]
    return yaml.safe_load(block)


@pytest.fixture(scope="module")
def high_five() -> tuple[int, str]:
    return run(["send-goal", "high_five", "{target_height: 0.3, hold_seconds: 0}", "--feedback"])


def test_send_goal_prints_the_goal_id_acceptance_feedback_and_result(high_five):
    code, out = high_five
    assert code == EXIT_SUCCEEDED, out
    lines = out.splitlines()
    assert lines[0].startswith("state: estimated (inekf, ") and lines[1].startswith(
        "plant menagerie")
    assert lines[2:4] == ["Waiting for an action server to become available...",
                          "Sending goal:"]
    assert section(out, "Sending goal") == {"target_height": 0.3, "hold_seconds": 0}
    assert "\nGoal accepted with ID: 1\n" in out
    feedback = [line for line in lines if line.startswith("Feedback [")]
    messages = [yaml.safe_load(line.split("]: ", 1)[1]) for line in feedback]
    phases = [message["phase"] for message in messages]
    assert list(dict.fromkeys(phases)) == HIGH_FIVE_PHASES
    progress = [message["progress"] for message in messages]
    assert progress[0] == 0.0 and progress[-1] == 1.0 and progress == sorted(progress)
    times = [float(line[len("Feedback ["):].split(" s]")[0]) for line in feedback]
    assert times[0] == pytest.approx(0.3, abs=2e-3)  # sent after the 0.3 s settle
    assert max(b - a for a, b in itertools.pairwise(times)) <= 0.02 + 1e-9
    assert section(out, "Result") == {
        "success": True,
        "message": "high five done: foot raised to 0.300 m, held 0 s, back on four feet"}
    assert lines[-1] == "Goal finished with status: SUCCEEDED"


def test_send_goal_to_another_action_without_feedback():
    code, out = run(["send-goal", "/stand", "duration_s: 0.5"])  # ROS 2's leading slash
    assert code == EXIT_SUCCEEDED, out
    assert section(out, "Sending goal") == {"duration_s": 0.5}
    assert "Feedback" not in out
    assert section(out, "Result") == {"success": True, "message": "reached the standing pose"}
    assert out.endswith("Goal finished with status: SUCCEEDED\n")


@pytest.mark.parametrize("type_name", ["go2_interfaces/action/Stand", "go2_interfaces/Stand",
                                       "Stand"])
def test_send_goal_takes_the_action_type_as_ros2_action_send_goal_does(type_name):
    code, out = run(["send-goal", "/stand", type_name, "{duration_s: 0.5}"])
    assert code == EXIT_SUCCEEDED, out
    assert section(out, "Sending goal") == {"duration_s": 0.5}
    assert out.endswith("Goal finished with status: SUCCEEDED\n")


def test_a_follow_joint_trajectory_goal_with_its_type_and_feedback_without_a_phase():
    goal = ("{trajectory: {joint_names: [FR_calf_joint], points: [{positions: [-1.9], "
            "time_from_start: {sec: 1}}]}}")
    code, out = run(["send-goal", "/follow_joint_trajectory",
                     "control_msgs/action/FollowJointTrajectory", goal, "--feedback"])
    assert code == EXIT_SUCCEEDED, out
    feedback = [yaml.safe_load(line.split("]: ", 1)[1]) for line in out.splitlines()
                if line.startswith("Feedback [")]
    assert {message["header"]["frame_id"] for message in feedback} == {""}
    reached = [message["desired"]["time_from_start"] for message in feedback]
    assert reached[0] == {"sec": 0, "nanosec": 0} and reached[-1]["sec"] == 1
    assert section(out, "Result") == {"error_code": 0, "error_string": (
        "goal reached: the FR leg holds the last point, in swing: the FR foot stays up and the "
        "robot stands on three feet; a Stand goal puts the foot down")}


def test_a_rejected_goal_prints_the_code_and_reason_and_exits_3():
    code, out = run(["send-goal", "high_five", "{target_height: 0.9, hold_seconds: 2}"])
    assert code == EXIT_REJECTED
    assert out.splitlines()[-1] == (
        f"Goal was rejected (code {INVALID_TARGET_HEIGHT}): target_height: expected a height "
        "of the front-right foot above the ground in [0.10, 0.50] m, received 0.9")


@pytest.mark.parametrize(("argv", "message"), [
    (["high_five", "{target_height: 0.4"],
     ("GOAL: not valid YAML at column 20: expected ',' or '}', but got '<stream end>'; "
      "expected a mapping \"{name: value, ...}\" with the goal's fields (go2-wbc interface "
      "ACTION)")),
    (["high_five", "[0.4, 2]"],
     ("GOAL: expected a YAML mapping \"{name: value, ...}\" with the goal's fields (go2-wbc "
      "interface ACTION); received '[0.4, 2]' (a list)")),
    (["high_five", "{target_hieght: 0.4}"],
     "GOAL: HighFiveGoal has no field 'target_hieght'; its fields: target_height, hold_seconds"),
    (["high_five", "{target_height: high}"],
     "GOAL: HighFiveGoal.target_height must be a real number; received 'high' (type str)"),
    (["high_five", "{hold_seconds: 2.5}"],
     "GOAL: HighFiveGoal.hold_seconds must be an integer; received 2.5 (type float)"),
    (["follow_joint_trajectory",
      "{trajectory: {joint_names: [FR_calf_joint], points: [{positions: [x]}]}}"],
     ("GOAL: FollowJointTrajectoryGoal.trajectory.points[0].positions[0] must be a real "
      "number; received 'x' (type str)")),
    (["follow_joint_trajectory", "{trajectory: {points: [{time: 1}]}}"],
     ("GOAL: FollowJointTrajectoryGoal.trajectory.points[0] (JointTrajectoryPoint) has no "
      "field 'time'; its fields: positions, velocities, accelerations, effort, "
      "time_from_start")),
    (["high5", "{}"],
     ("ACTION: no action named 'high5'; served actions: follow_joint_trajectory, high_five, "
      "sit, stand, walk")),
    (["/high_five", "go2_interfaces/action/Stand", "{target_height: 0.4}"],
     ("TYPE: the 'high_five' action is of type go2_interfaces/action/HighFive; received "
      "go2_interfaces/action/Stand")),
    (["follow_joint_trajectory", "go2_interfaces/action/FollowJointTrajectory", "{}"],
     ("TYPE: unknown action type 'go2_interfaces/action/FollowJointTrajectory' "
      "(FollowJointTrajectory is control_msgs/action/FollowJointTrajectory); valid action "
      "types: control_msgs/action/FollowJointTrajectory, go2_interfaces/action/HighFive, "
      "go2_interfaces/action/Sit, go2_interfaces/action/Stand, go2_interfaces/action/Walk (or "
      "the last part alone, e.g. Walk)")),
    (["high_five", "go2_interfaces/action/HighFive"],
     ("GOAL: 'go2_interfaces/action/HighFive' is an action type "
      "(go2_interfaces/action/HighFive), not a goal; expected ACTION [TYPE] GOAL together, "
      "before any option, the goal a YAML mapping \"{name: value, ...}\" with the goal's "
      "fields (go2-wbc interface ACTION)")),
    (["stand", "{duration_s: 1}", "--timeout", "0"],
     "--timeout: expected a number of seconds > 0, received '0'"),
])
def test_bad_input_exits_2_with_one_line_naming_the_field(argv, message, capsys):
    line = usage_error(["send-goal", *argv], capsys)
    assert line == f"go2-wbc send-goal: error: {message} (see 'go2-wbc send-goal --help')"


def test_actions_lists_what_the_simulated_go2_serves_with_types():
    code, out = run(["actions"])
    assert code == EXIT_SUCCEEDED
    assert out == ("follow_joint_trajectory [control_msgs/action/FollowJointTrajectory]\n"
                   "high_five [go2_interfaces/action/HighFive]\n"
                   "sit [go2_interfaces/action/Sit]\n"
                   "stand [go2_interfaces/action/Stand]\n"
                   "walk [go2_interfaces/action/Walk]\n")
    runner = ControlLoop.simulated().runner  # the list is the served one
    assert {name: runner.server(name).action_type for name in runner.server_names} == (
        GO2_ACTIONS)


@pytest.mark.parametrize("name", ["high_five", "/high_five", "HighFive", "go2_interfaces/HighFive",
                                  "go2_interfaces/action/HighFive"])
def test_interface_prints_the_action_definition(name):
    code, out = run(["interface", name])
    assert code == EXIT_SUCCEEDED
    assert out == HIGH_FIVE.interface_path.read_text()
    assert "float32 target_height" in out and out.count("---") == 2


def test_interface_of_every_type_and_an_unknown_name(capsys):
    for action_type in ACTION_TYPES.values():
        for name in (action_type.name, action_type.type_name):  # as ros2 interface show
            assert run(["interface", name])[1] == action_type.interface_path.read_text()
    line = usage_error(["interface", "foo"], capsys)
    assert line == (
        "go2-wbc interface: error: ACTION: no action or interface named 'foo'; actions: "
        "follow_joint_trajectory, high_five, sit, stand, walk; interfaces: "
        "control_msgs/action/FollowJointTrajectory, go2_interfaces/action/HighFive, "
        "go2_interfaces/action/Sit, go2_interfaces/action/Stand, go2_interfaces/action/Walk (or "
        "the last part alone, e.g. HighFive) (see 'go2-wbc interface --help')")


def exit_code_table() -> dict[int, str]:
    """The help's exit status table: code -> its text (continuation lines joined)."""
    table: dict[int, str] = {}
    code = None
    for line in EXIT_CODES_HELP.splitlines()[1:]:
        first, _, rest = line.strip().partition("  ")
        if first.isdigit():
            code = int(first)
            table[code] = rest.strip()
        elif code is not None:
            table[code] += " " + line.strip()
    return table


def test_the_help_says_the_exit_code_an_action_that_is_not_served_gives(capsys):
    table = exit_code_table()
    assert sorted(table) == [0, 1, 2, 3, 4, 130]
    assert "an action that is not served" in table[2]
    assert "action" not in table[4]  # it said 4 here, and the code gave 2
    for argv in (["send-goal", "nonexistent", "{}"], ["interface", "nonexistent"]):
        usage_error(argv, capsys)  # exit 2, one line
    with pytest.raises(SystemExit) as exc:
        main(["send-goal", "--help"])
    assert exc.value.code == 0
    assert EXIT_CODES_HELP in capsys.readouterr().out
