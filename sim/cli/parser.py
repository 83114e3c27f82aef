"""The ``go2-wbc`` argument parser: its commands, their options, their help."""

from __future__ import annotations

import argparse

from actions.go2.go2_actions import HIGH_FIVE_ACTION, SIT_ACTION, STAND_ACTION, WALK_ACTION
from actions.go2.go2_interfaces import SitGoal, StandGoal
from actions.go2.high_five_behaviour import MAX_HOLD_S
from actions.go2.pose_behaviour import MAX_DURATION_S, MIN_DURATION_S
from actions.go2.walk_behaviour import MAX_DISTANCE_M, MAX_WALK_S
from sim.cli import dds_goal, goal_commands
from sim.cli.arg_types import float_in, trajectory_file, whole_in
from sim.cli.bridge import add_bridge_command
from sim.cli.check import add_check_command
from sim.cli.dds_options import add_dds_options
from sim.cli.exit_codes import EXIT_CODES_HELP
from sim.cli.options import CliParser, add_plant_options, run_options
from sim.cli.recording_options import RECORDING_HELP
from sim.cli.replay import add_replay_command
from sim.cli.ros2_command import add_ros2_commands
from sim.cli.run_dds import add_run_command
from sim.cli.send_goal import add_action_commands
from sim.cli.settings import add_settings
from sim.cli.teleop import add_teleop_command
from sim.cli.trajectory_file import TRAJECTORY_FORMAT_HELP
from sim.cli.version import version_text
from sim.episode import episode_default
from wbc.locomotion.gait import VelocityLimits
from wbc.motions.leg_lift import MAX_HEIGHT_M, MIN_HEIGHT_M

EXAMPLES_HELP = """\
examples:
  go2-wbc high-five                         # 0.40 m, hold 2 s, headless
  go2-wbc high-five --height 0.3 --hold 0 --metrics
  go2-wbc high-five --video hf.mp4 --plot hf.png --report hf.json --log hf.npz
  go2-wbc high-five --viewer --set video.overlay=all  # CoM, polygon, forces, foot target
  go2-wbc high-five --push 40,0.1 --set push.at_s=3 --set push.dir_deg=90
  go2-wbc high-five --cancel-at 2.5         # ends CANCELED with the foot down
  go2-wbc stand; go2-wbc sit --duration 1.5
  go2-wbc trajectory wave.yaml              # format: go2-wbc trajectory --help
  go2-wbc walk --forward 0.5 --duration 5 --video walk.mp4 --plot walk.png
  go2-wbc high-five --plant identified --set plant.calf_friction_loss=1.4
  go2-wbc high-five --set run.control_rate_hz=500   # the GO2's usual low-level rate
  go2-wbc high-five --set estimator.trust_timeout_s=0.05 --set controller.gains.com_kp=200
  go2-wbc high-five --set help              # every setting, its unit and default
  go2-wbc run --dds; go2-wbc high-five --dds  # a controller on DDS and a goal to it
  go2-wbc high-five --mcap hf.mcap; go2-wbc replay hf.mcap  # Foxglove/Lichtblick, replay

"""


def build_parser() -> argparse.ArgumentParser:
    """The ``go2-wbc`` argument parser."""
    parser = CliParser(
        prog="go2-wbc",
        description="Send an action goal to a simulated Unitree GO2 under whole-body\n"
                    "control and print its feedback and result, like a ROS 2 action client.",
        epilog=EXAMPLES_HELP + EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=version_text(),
                        help="print the installed version, licence and source URL, and exit")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    common = run_options()

    def add(name: str, help_text: str, epilog: str = "") -> argparse.ArgumentParser:
        command = sub.add_parser(name, parents=[common], help=help_text,
                                 description=help_text,
                                 epilog=epilog + RECORDING_HELP + EXIT_CODES_HELP,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
        command.set_defaults(parser=command)
        return command

    high_five = add(HIGH_FIVE_ACTION.replace("_", "-"),
                    "raise the front-right foot, hold it up, put it back down")
    goal = episode_default("goal")  # the Episode's default goal is this command's
    high_five.add_argument(
        "--height", type=float_in(MIN_HEIGHT_M, MAX_HEIGHT_M, what="a height", unit="m"),
        default=goal.target_height, metavar="M",
        help=f"foot height above the ground [m], in [{MIN_HEIGHT_M:.2f}, {MAX_HEIGHT_M:.2f}] "
             f"(default: {goal.target_height:.2f})")
    high_five.add_argument(
        "--hold", type=whole_in(0, MAX_HOLD_S, what="a whole number of seconds"),
        default=goal.hold_seconds, metavar="S",
        help=f"seconds to hold the foot up [s], a whole number in [0, {MAX_HOLD_S}] "
             f"(default: {goal.hold_seconds})")
    add_dds_options(high_five.add_argument_group("dds"),
                    flag_help="send the goal over DDS to a running 'go2-wbc run --dds' "
                              "instead of simulating (no simulation option then; default: "
                              "simulate)")
    high_five.set_defaults(run=goal_commands.high_five, dds_run=dds_goal.high_five)

    duration = float_in(MIN_DURATION_S, MAX_DURATION_S, what="a duration", unit="s", fmt="g")
    for name, verb, run, goal_type in (
            (STAND_ACTION, "rise to the standing pose", goal_commands.stand, StandGoal),
            (SIT_ACTION, "lower the body to the lying pose", goal_commands.sit, SitGoal)):
        pose = add(name, f"{verb} on four feet")
        default_s = goal_type().duration_s  # the message's default
        pose.add_argument("--duration", type=duration, default=default_s, metavar="S",
                          help=f"time to reach the pose [s], in [{MIN_DURATION_S:g}, "
                               f"{MAX_DURATION_S:g}] (default: {default_s})")
        pose.set_defaults(run=run)

    trajectory = add("trajectory", "follow a joint trajectory read from a YAML or JSON file "
                     "(FollowJointTrajectory)", TRAJECTORY_FORMAT_HELP)
    trajectory.add_argument("file", type=trajectory_file, metavar="FILE",
                            help="the trajectory file (format below)")
    trajectory.set_defaults(run=goal_commands.trajectory)

    walk = add(WALK_ACTION, "trot at a velocity (the base's heading frame) for a duration or a "
                            "distance, then stop on four loaded feet")
    limits = VelocityLimits()
    for flag, limit, what, unit in (
            ("--forward", limits.forward_mps, "forward velocity", "m/s"),
            ("--lateral", limits.lateral_mps, "leftward velocity", "m/s"),
            ("--yaw-rate", limits.yaw_rate_radps, "turning rate (counter-clockwise)", "rad/s")):
        walk.add_argument(flag, type=float_in(-limit, limit, what=f"a {what}", unit=unit,
                                              fmt="g"),
                          default=0.0, metavar=unit.split("/")[0].upper(),
                          help=f"{what} [{unit}], in [{-limit:g}, {limit:g}] (default: 0)")
    span = walk.add_mutually_exclusive_group()
    span.add_argument("--duration", type=float_in(0.0, MAX_WALK_S, what="a duration", unit="s",
                                                  fmt="g"),
                      metavar="S", help=f"walk this long [s], in (0, {MAX_WALK_S:g}] "
                                        f"(default: {goal_commands.WALK_DEFAULT_S:g} unless "
                                        "--distance is given)")
    span.add_argument("--distance", type=float_in(0.0, MAX_DISTANCE_M, what="a path length",
                                                  unit="m", fmt="g"),
                      metavar="M", help=f"walk this path length [m], in (0, "
                                        f"{MAX_DISTANCE_M:g}] (default: none)")
    walk.set_defaults(run=goal_commands.walk)

    stand_pd = sub.add_parser("stand-pd", help="stand under a joint PD (baseline, no QP)",
                              description="Stand under a joint PD with gravity compensation "
                                          "(the baseline without the QP); print the drift.")
    stand_pd.add_argument("--duration", type=float_in(0.001, 60.0, what="a duration", unit="s",
                                                      fmt="g"),
                          default=3.0, metavar="S",
                          help="simulated seconds [s], in [0.001, 60] (default: 3.0)")
    simulation = stand_pd.add_argument_group("simulation")
    add_plant_options(simulation)
    add_settings(stand_pd, simulation, ("plant", "rates"))
    stand_pd.set_defaults(run=goal_commands.stand_pd, parser=stand_pd)
    add_action_commands(sub)
    sub.choices["send-goal"].set_defaults(dds_run=dds_goal.send_goal)
    add_bridge_command(sub)
    add_run_command(sub)
    add_check_command(sub)
    add_replay_command(sub)
    add_ros2_commands(sub)  # after run and send-goal: it adds --ros2 to them
    add_teleop_command(sub)
    return parser
