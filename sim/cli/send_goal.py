"""``go2-wbc send-goal``, ``actions`` and ``interface``: ``ros2 action`` habits on a simulated GO2.

``go2-wbc send-goal /high_five go2_interfaces/action/HighFive "{...}" --feedback`` does what
``ros2 action send_goal`` does with the same arguments (the type may be left out), for any
served action, against a fresh simulated GO2: it prints the goal, its id and acceptance, a
line per feedback message with ``--feedback``, the result and the final status. ``go2-wbc
actions`` is ``ros2 action list -t``; ``go2-wbc interface go2_interfaces/action/HighFive`` (or
``high_five``) is ``ros2 interface show``.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from typing import IO, TYPE_CHECKING, Any

import yaml

from actions.action_type import ActionType, action_type_named
from actions.go2.go2_actions import GO2_ACTIONS
from actions.go2.go2_interfaces import ACTION_TYPES
from actions.message_fields import set_message_fields
from actions.responses import FeedbackMessage
from sim.cli.dds_options import add_dds_options
from sim.cli.episode_options import goal_episode
from sim.cli.exit_codes import EXIT_CODES_HELP, EXIT_SUCCEEDED, exit_code
from sim.cli.options import add_plant_options, add_state_options
from sim.cli.output import plant_line, state_line
from sim.cli.settings import add_settings
from sim.episode_loop import startup_objects_frozen
from sim.episode_result import UNAVAILABLE, EpisodeListener, EpisodeResult
from sim.episode_runner import EpisodeRunner
from wbc.core.errors import WbcError

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from sim.episode_result import EpisodeEvent, FeedbackSample

#: Significant digits of the numbers in a feedback line.
FEEDBACK_DIGITS = 6
#: Default longest run of a goal [s of simulated time] before send-goal cancels it.
DEFAULT_TIMEOUT_S = 300.0

SEND_GOAL_HELP = """\
the arguments are those of ros2 action send_goal: the action, its type (optional here; if
given, it must be the action's: go2_interfaces/action/HighFive, go2_interfaces/HighFive or
HighFive), and the goal as a YAML (or JSON) mapping of its fields; fields left out keep their
defaults (0, empty). Nested messages are mappings, a duration is {sec: 1, nanosec: 0} or a
number of seconds. 'go2-wbc actions' lists the actions and their types, 'go2-wbc interface
ACTION' shows the fields.

examples:
  go2-wbc send-goal high_five "{target_height: 0.4, hold_seconds: 2}" --feedback
  go2-wbc send-goal /high_five go2_interfaces/action/HighFive "{target_height: 0.4}"
  go2-wbc send-goal stand "{duration_s: 1.5}"
  go2-wbc send-goal follow_joint_trajectory "{trajectory: {joint_names: [FR_calf_joint],
      points: [{positions: [-1.9], time_from_start: {sec: 1}}]}}" --feedback

output: the goal, 'Goal accepted with ID: N' (or the rejection's code and reason), with
--feedback one line per feedback message with its simulated time, the result, and 'Goal
finished with status: SUCCEEDED' (or CANCELED, ABORTED). An action that is not served, a type
that is not the action's, bad YAML, an unknown field or a value of the wrong type is a usage
error (exit 2) naming the argument or the field.

"""


# --------------------------------------------------------------------------- argument types


def _served_action(text: str) -> tuple[str, ActionType]:
    """An argparse type: a served action's name (a leading ``/`` as in ROS 2 is allowed)."""
    name = text.removeprefix("/")
    if name not in GO2_ACTIONS:
        raise argparse.ArgumentTypeError(
            f"no action named {text!r}; served actions: {', '.join(sorted(GO2_ACTIONS))}")
    return name, GO2_ACTIONS[name]


def _action_type(text: str) -> ActionType:
    """An argparse type: an action type, in any form ``ros2 action send_goal`` takes
    (``go2_interfaces/action/HighFive``, ``go2_interfaces/HighFive``, ``HighFive``)."""
    try:
        return action_type_named(text, ACTION_TYPES.values())
    except WbcError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _action_or_interface(text: str) -> ActionType:
    """An argparse type: a served action's name (``high_five``) or an interface, by its full
    name as ``ros2 interface show`` takes it (``go2_interfaces/action/HighFive``) or shorter
    (``go2_interfaces/HighFive``, ``HighFive``)."""
    name = text.removeprefix("/")
    if name in GO2_ACTIONS:
        return GO2_ACTIONS[name]
    try:
        return action_type_named(text, ACTION_TYPES.values())
    except WbcError:
        pass
    interfaces = ", ".join(sorted(t.type_name for t in ACTION_TYPES.values()))
    raise argparse.ArgumentTypeError(
        f"no action or interface named {text!r}; actions: {', '.join(sorted(GO2_ACTIONS))}; "
        f"interfaces: {interfaces} (or the last part alone, e.g. HighFive)")


def _goal_mapping(text: str) -> dict[Any, Any]:
    """An argparse type: the goal as a YAML/JSON mapping (an empty text is ``{}``)."""
    example = '"{name: value, ...}" with the goal\'s fields (go2-wbc interface ACTION)'
    if "{" not in text and ":" not in text:
        try:  # the type given as the last argument: the goal itself is missing
            type_name = action_type_named(text.strip(), ACTION_TYPES.values()).type_name
        except WbcError:
            pass
        else:
            raise argparse.ArgumentTypeError(
                f"{text!r} is an action type ({type_name}), not a goal; expected ACTION [TYPE] "
                f"GOAL together, before any option, the goal a YAML mapping {example}")
    try:
        data = yaml.safe_load(text)
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark
        where = f" at column {mark.column + 1}" if mark is not None and mark.line == 0 else (
            f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else "")
        raise argparse.ArgumentTypeError(
            f"not valid YAML{where}: {err.problem}; expected a mapping {example}"
        ) from None
    except yaml.YAMLError as err:
        raise argparse.ArgumentTypeError(f"not valid YAML: {err}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise argparse.ArgumentTypeError(
            f"expected a YAML mapping {example}; received {text!r} (a {type(data).__name__})")
    return data


def _sim_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(
            f"expected a number of seconds > 0, received {text!r}")
    return value


# --------------------------------------------------------------------------- registration


def add_action_commands(sub: Any) -> None:
    """Add ``send-goal``, ``actions`` and ``interface`` to the ``go2-wbc`` subcommands.

    Args:
        sub: The subparsers object of the ``go2-wbc`` parser.
    """
    send = sub.add_parser(
        "send-goal", help="send a goal given as YAML to any action (ros2 action send_goal)",
        description="Send a goal, given as a YAML mapping, to an action of a simulated GO2\n"
                    "and print its id, acceptance, feedback and result, like ros2 action "
                    "send_goal.",
        epilog=SEND_GOAL_HELP + EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    send.add_argument("action", type=_served_action, metavar="ACTION",
                      help="the action's name, as 'go2-wbc actions' lists it (e.g. high_five)")
    send.add_argument("type", type=_action_type, nargs="?", metavar="TYPE",
                      help="the action's type, as 'go2-wbc actions' lists it (e.g. "
                           "go2_interfaces/action/HighFive, or go2_interfaces/HighFive, "
                           "HighFive); optional: when given, it must be the action's")
    send.add_argument("goal", type=_goal_mapping, metavar="GOAL",
                      help='the goal\'s fields as YAML, e.g. "{target_height: 0.4, '
                           'hold_seconds: 2}"')
    send.add_argument("-f", "--feedback", action="store_true",
                      help="print every feedback message, one line each (default: off)")
    send.add_argument("--timeout", type=_sim_seconds, default=DEFAULT_TIMEOUT_S,
                      metavar="SECONDS",
                      help="cancel the goal if it has not ended after this many seconds of "
                           f"simulated time (default: {DEFAULT_TIMEOUT_S:g})")
    simulation = send.add_argument_group("simulation")
    add_plant_options(simulation)
    add_state_options(simulation)
    add_settings(send, simulation, ("controller", "estimator", "sensors", "plant", "rates",
                                    "state"))
    add_dds_options(send.add_argument_group("dds"),
                    flag_help="send the goal over DDS to a running 'go2-wbc run --dds' "
                              "instead of simulating (--timeout is then wall-clock seconds; "
                              "no simulation option; default: simulate)")
    send.set_defaults(run=_send_goal, parser=send)

    listing = sub.add_parser(
        "actions", help="list the served actions with their interfaces (ros2 action list -t)",
        description="List the actions a simulated GO2 serves, each with its interface.")
    listing.set_defaults(run=_list_actions, parser=listing)

    interface = sub.add_parser(
        "interface", help="print an action's .action definition (ros2 interface show)",
        description="Print the .action definition of an action: its goal, result and "
                    "feedback fields.")
    interface.add_argument("interface", type=_action_or_interface, metavar="ACTION",
                           help="an action name (high_five) or an interface name "
                                "(go2_interfaces/action/HighFive, go2_interfaces/HighFive or "
                                "HighFive)")
    interface.set_defaults(run=_show_interface, parser=interface)


# --------------------------------------------------------------------------- subcommands


def _list_actions(args: argparse.Namespace, stream: IO[str] | None = None) -> int:
    stream = stream or sys.stdout
    for name in sorted(GO2_ACTIONS):
        stream.write(f"{name} [{GO2_ACTIONS[name].type_name}]\n")
    return EXIT_SUCCEEDED


def _show_interface(args: argparse.Namespace, stream: IO[str] | None = None) -> int:
    (stream or sys.stdout).write(args.interface.interface_path.read_text(encoding="utf-8"))
    return EXIT_SUCCEEDED


def checked_goal(args: argparse.Namespace) -> tuple[str, Any]:
    """``send-goal``'s action name and goal message, checked against the action's type (a
    usage error names TYPE or the GOAL's field)."""
    name, action_type = args.action
    if args.type is not None and args.type is not action_type:
        args.parser.error(
            f"TYPE: the '{name}' action is of type {action_type.type_name}; received "
            f"{args.type.type_name}")
    try:
        goal = set_message_fields(action_type.Goal(), args.goal).validated_copy()
    except WbcError as err:
        args.parser.error(f"GOAL: {err}")
    return name, goal


def _send_goal(args: argparse.Namespace) -> int:
    return SendGoal(args, *checked_goal(args)).run()


class SendGoal(EpisodeListener):
    """Sends one goal to a fresh simulated GO2 and prints what ``ros2 action send_goal`` does.

    Args:
        args: The parsed options (the episode, ``feedback``, ``timeout``).
        action_name: The action to send the goal to.
        goal: The goal, already validated.
        stream: Where to print (standard output by default).
    """

    def __init__(self, args: argparse.Namespace, action_name: str, goal: Any, *,
                 stream: IO[str] | None = None):
        self.args = args
        self.action_name = action_name
        self.goal = goal
        self.stream = stream or sys.stdout

    def say(self, text: str) -> None:
        """Print ``text`` (one or more lines)."""
        self.stream.write(text + "\n")
        self.stream.flush()

    def run(self) -> int:
        """Run the goal to its end; return the exit code."""
        args = self.args
        episode = goal_episode(args, self.action_name, self.goal, timeout_s=args.timeout)
        self.say(state_line(episode))
        self.say(plant_line(episode))
        runner = self.runner = EpisodeRunner(episode, listener=self)
        with startup_objects_frozen():
            return self._finish(runner.run())

    def _finish(self, result: EpisodeResult) -> int:
        if result.status == UNAVAILABLE:
            print(f"go2-wbc: the '{self.action_name}' action server is not available",
                  file=sys.stderr)
        if result.wrapped is not None:
            self.say("\nResult:\n" + yaml_block(result.wrapped.result) + "\n")
            self.say(f"Goal finished with status: {result.status}")
        return exit_code(result)

    # -- what the runner tells -------------------------------------------------------------

    def goal_sending(self, runner: EpisodeRunner, now_s: float) -> None:
        self.say("Waiting for an action server to become available...")
        self.say("Sending goal:\n" + yaml_block(self.goal) + "\n")

    def goal_response(self, handle: ClientGoalHandle, now_s: float) -> None:
        if handle.accepted:
            self.say(f"Goal accepted with ID: {handle.goal_id}\n")
        else:
            rejection = handle.rejection
            self.say(f"Goal was rejected (code {rejection.code}): {rejection.message}")

    def feedback(self, sample: FeedbackSample, message: FeedbackMessage) -> None:
        if not self.args.feedback:
            return
        fields = rounded_fields(dataclasses.asdict(message.feedback))
        text = yaml.safe_dump(fields, default_flow_style=True, sort_keys=False,
                              width=math.inf).strip()
        self.say(f"Feedback [{self.runner.loop.robot.time_s:7.3f} s]: {text}")

    def event(self, event: EpisodeEvent) -> None:
        if event.event == "timeout":
            self.say(f"No result after {self.args.timeout:g} s of simulated time: "
                     "canceling the goal")
        elif event.event == "interrupted":
            self.say("Interrupted: canceling the goal")


class _BlockDumper(yaml.SafeDumper):
    """Mappings as blocks (one field a line), arrays of numbers or strings on one line."""


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    flow = all(not isinstance(item, dict | list) for item in data)
    return dumper.represent_sequence("tag:yaml.org,2002:seq", data, flow_style=flow)


def _represent_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
    return dumper.represent_mapping("tag:yaml.org,2002:map", data.items(), flow_style=False)


_BlockDumper.add_representer(list, _represent_list)
_BlockDumper.add_representer(dict, _represent_dict)


def yaml_block(message: Any) -> str:
    """A message as an indented YAML block, as ``ros2 action send_goal`` prints one."""
    text = yaml.dump(dataclasses.asdict(message), Dumper=_BlockDumper, sort_keys=False,
                     width=100)
    return "\n".join(f"    {line}" for line in text.rstrip("\n").splitlines())


def rounded_fields(value: Any) -> Any:
    """``value`` with every float rounded to :data:`FEEDBACK_DIGITS` significant digits."""
    if isinstance(value, float):
        return float(f"{value:.{FEEDBACK_DIGITS}g}")
    if isinstance(value, dict):
        return {key: rounded_fields(item) for key, item in value.items()}
    if isinstance(value, list):
        return [rounded_fields(item) for item in value]
    return value

