"""``go2-wbc ros2``, ``run --dds --ros2`` and ``send-goal --ros2``: the controller as a ROS 2 node
and a ROS 2 action client (the ``ros2`` extra, :mod:`go2_ros2`; docs/ros2.md).

Nothing here imports rclpy: the commands import :mod:`go2_ros2` when they run, and say how to
install the extra when it is missing.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import signal
import sys
from typing import IO, Any

import yaml

from actions.robot.robot_interface import STATE_SOURCES
from sim.cli.arg_types import float_in, output_file, whole_in
from sim.cli.exit_codes import (
    EXIT_CODES_HELP,
    EXIT_INTERRUPTED,
    EXIT_NOT_SUCCEEDED,
    EXIT_REJECTED,
    EXIT_SUCCEEDED,
    EXIT_UNAVAILABLE,
)
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS
from sim.sensor_model import DEFAULT_SENSORS, SENSOR_PRESETS

#: What to do when the extra is not there.
INSTALL_HINT = ("the ros2 extra is not installed: pip install 'go2-wbc[ros2]', then "
                "python -m go2_ros2.interface_build (from a clone: make install-ros2)")
#: Control rates [Hz] of the simulated robot.
RATES_HZ = (1000, 500)

ROS2_HELP = """\
the node serves the actions /high_five, /stand, /sit, /walk and
/joint_trajectory_controller/follow_joint_trajectory (go2_interfaces/action/HighFive, Stand,
Sit, Walk; control_msgs/action/FollowJointTrajectory), walks on geometry_msgs/Twist from
/cmd_vel (linear.x, linear.y, angular.z; stopped 0.5 s after the last one), and publishes
/joint_states, /imu, /odom (from the state estimator) and /clock (the simulated time: clients
use use_sim_time:=true to stamp with it). Goals are accepted or rejected for the same reasons
as everywhere in go2-wbc (logged by the node: ROS 2's goal response carries no reason); a goal
while another runs is rejected.

examples:
  go2-wbc ros2                                           # the simulated GO2 as a ROS 2 node
  go2-wbc ros2 --namespace robot1                        # /robot1/high_five, /robot1/odom...
  go2-wbc ros2 --ros-args --remap high_five:=wave        # any ROS 2 argument, last
  go2-wbc send-goal high_five "{target_height: 0.4, hold_seconds: 2}" --ros2 --feedback

"""


def add_ros2_options(group: Any) -> None:
    """``--node-name``, ``--namespace`` and ``--ros-args ...`` (which takes the rest of the
    command line, as in ROS 2)."""
    from go2_ros2.ros_names import DEFAULT_NODE_NAME

    group.add_argument("--node-name", default=DEFAULT_NODE_NAME, metavar="NAME",
                       help=f"the ROS 2 node's name (default: {DEFAULT_NODE_NAME})")
    group.add_argument("--namespace", default="", metavar="NS",
                       help="the node's namespace; its actions and topics are under it "
                            "(default: none, /high_five)")
    group.add_argument("--ros-args", nargs=argparse.REMAINDER, default=[], metavar="ARG",
                       help="ROS 2 arguments, last on the line: --remap FROM:=TO, -p NAME:="
                            "VALUE, --log-level LEVEL (default: none)")


def add_ros2_commands(sub: Any) -> None:
    """Add ``ros2`` to the ``go2-wbc`` subcommands, and ``--ros2`` to ``run`` and
    ``send-goal`` (registered before this)."""
    ros2 = sub.add_parser(
        "ros2", help="run the simulated GO2 as a ROS 2 node (the ros2 extra)",
        description="Run the simulated GO2 under whole-body control, on the wall clock, as a "
                    "ROS 2 node: its actions served by rclpy, its state published, until "
                    "Ctrl-C.",
        epilog=ROS2_HELP + EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    sim = ros2.add_argument_group("simulation")
    sim.add_argument("--control-rate", type=int, choices=RATES_HZ, default=RATES_HZ[0],
                     metavar="HZ", help="control rate [Hz]: 1000 or 500 (default: 1000)")
    sim.add_argument("--sim-plant", choices=tuple(PLANT_PRESETS), default=DEFAULT_PLANT,
                     help=f"the plant's preset (default: {DEFAULT_PLANT})")
    sim.add_argument("--sim-sensors", choices=tuple(SENSOR_PRESETS), default=DEFAULT_SENSORS,
                     help=f"the sensors' preset (default: {DEFAULT_SENSORS})")
    sim.add_argument("--sensor-seed", type=whole_in(0, 2**31 - 1, what="a seed"), default=0,
                     metavar="N", help="seed of the sensors' noise and biases (default: 0)")
    sim.add_argument("--state", choices=STATE_SOURCES, default=STATE_SOURCES[0],
                     help=f"what the controller reads (default: {STATE_SOURCES[0]})")
    sim.add_argument("--duration", type=float_in(0.01, 1e6, what="a duration", unit="s",
                                                 fmt="g"), metavar="S",
                     help="exit after this many seconds of simulated time (default: run "
                          "until Ctrl-C or SIGTERM)")
    sim.add_argument("--truth-report", type=output_file(".json"), metavar="FILE.json",
                     help="at exit, write each goal's figures measured on the simulator's "
                          "truth (raised foot against its target, tilt, the feet's forces at "
                          "the end, the estimate's errors) and the true base pose every 4 ms "
                          "(kept in memory: for runs of minutes; default: none)")
    add_ros2_options(ros2.add_argument_group("ROS 2"))
    ros2.set_defaults(run=run_ros2_node, parser=ros2)

    run = sub.choices["run"]
    group = run.add_argument_group("ROS 2")
    group.add_argument("--ros2", action="store_true",
                       help="also serve the actions and publish the state as a ROS 2 node "
                            "(the ros2 extra; docs/ros2.md; default: DDS actions only)")
    add_ros2_options(group)

    send = sub.choices["send-goal"]
    send_group = send.add_argument_group("ROS 2")
    send_group.add_argument("--ros2", action="store_true",
                            help="send the goal to a running ROS 2 node ('go2-wbc ros2' or "
                                 "'run --dds --ros2') with rclpy (--timeout is then "
                                 "wall-clock seconds; default: simulate)")
    send_group.add_argument("--namespace", default="", metavar="NS",
                            help="with --ros2: the node's namespace (default: none)")
    send_group.add_argument("--ros-args", nargs=argparse.REMAINDER, default=[], metavar="ARG",
                            help="with --ros2: ROS 2 arguments, last (e.g. --remap "
                                 "high_five:=wave; default: none)")
    simulate = send.get_default("run")

    def send_goal(args: argparse.Namespace) -> int:
        if not args.ros2:
            return int(simulate(args))
        return send_goal_ros2(args)

    send.set_defaults(run=send_goal)


def _missing_extra(err: ImportError) -> int:
    print(f"go2-wbc: {INSTALL_HINT} ({err})", file=sys.stderr)
    return EXIT_UNAVAILABLE


def run_ros2_node(args: argparse.Namespace, *, stream: IO[str] | None = None) -> int:
    """``go2-wbc ros2``: the simulated GO2 as a ROS 2 node, until Ctrl-C, SIGTERM or
    ``--duration``."""
    out = stream or sys.stdout
    try:
        from go2_ros2.go2_node import Go2Node
        from go2_ros2.paced_loop import PacedLoop
    except ImportError as err:
        return _missing_extra(err)
    from sim.control_loop import ControlLoop
    from sim.episode_loop import startup_objects_frozen

    loop = ControlLoop.simulated(plant=args.sim_plant, sensors=args.sim_sensors,
                                 sensor_seed=args.sensor_seed, state=args.state,
                                 control_period_s=1.0 / args.control_rate)
    node = Go2Node(loop, node_name=args.node_name, namespace=args.namespace,
                   ros_args=args.ros_args, sim_time=True)
    paced = PacedLoop(loop)
    report = None
    if args.truth_report is not None:
        from go2_ros2.truth_report import TruthReport

        report = TruthReport(loop)
        loop.hooks.append(report.tick_hook)
    previous = {sig: signal.signal(sig, lambda *_: paced.request_stop())
                for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        node.start()
        out.write(f"ROS 2 node /{node.node.get_fully_qualified_name().lstrip('/')} (RMW "
                  f"{node.rmw_name}): the simulated GO2 at {args.control_rate} Hz on the wall "
                  f"clock; actions {', '.join(node.action_names)}; topics "
                  f"{', '.join(node.topic_names)}; Ctrl-C to exit\n")
        out.flush()
        with startup_objects_frozen():
            paced.run(duration_s=args.duration)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        node.close()
    out.write(f"stopped at {loop.robot.time_s:.3f} s of simulated time ({paced.ticks} ticks, "
              f"{paced.resyncs} times behind the wall clock by more than 50 ms, "
              f"{node.state.published} state publications)\n")
    if report is not None:
        goals = report.write(args.truth_report)
        out.write(f"truth report: {args.truth_report} ({goals} goals)\n")
    return EXIT_SUCCEEDED


def start_ros2_node(args: argparse.Namespace, loop: Any, say: Any) -> Any:
    """``run --dds --ros2``: a started :class:`go2_ros2.go2_node.Go2Node` on ``loop`` (the
    robot's own clock: no ``/clock``), or ``None`` without ``--ros2``.

    Raises:
        SystemExit: The extra is not installed (exit status 4, saying how to install it).
    """
    if not getattr(args, "ros2", False):
        return None
    try:
        from go2_ros2.go2_node import Go2Node
    except ImportError as err:
        raise SystemExit(_missing_extra(err)) from err
    # Its threads just below the control loop's SCHED_FIFO priority (when permitted).
    node = Go2Node(loop, node_name=args.node_name, namespace=args.namespace,
                   ros_args=args.ros_args, sim_time=False,
                   thread_priority=max(args.rt_priority - 1, 0))
    node.start()
    say(f"ROS 2 node {node.node.get_fully_qualified_name()} (RMW {node.rmw_name}): actions "
        f"{', '.join(node.action_names)}; topics {', '.join(node.topic_names)}")
    return node


def send_goal_ros2(args: argparse.Namespace) -> int:
    """``send-goal ... --ros2``: the goal checked as ``send-goal`` checks it, then sent with
    rclpy (:func:`go2_ros2.ros2_goal_client.send_goal_over_ros2`)."""
    from sim.cli.send_goal import checked_goal, rounded_fields, yaml_block

    name, goal = checked_goal(args)
    try:
        from go2_ros2.ros2_goal_client import Outcome, send_goal_over_ros2
    except ImportError as err:
        return _missing_extra(err)

    def say(text: str) -> None:
        sys.stdout.write(text + "\n")
        sys.stdout.flush()

    def feedback_line(message: Any) -> str:
        fields = rounded_fields(dataclasses.asdict(message))
        return yaml.safe_dump(fields, default_flow_style=True, sort_keys=False,
                              width=math.inf).strip()

    outcome = send_goal_over_ros2(
        name, goal, say=say, block=yaml_block,
        feedback_line=feedback_line if args.feedback else None, timeout_s=args.timeout,
        namespace=args.namespace, ros_args=args.ros_args)
    return {Outcome.SUCCEEDED: EXIT_SUCCEEDED, Outcome.NOT_SUCCEEDED: EXIT_NOT_SUCCEEDED,
            Outcome.REJECTED: EXIT_REJECTED, Outcome.UNAVAILABLE: EXIT_UNAVAILABLE,
            Outcome.INTERRUPTED: EXIT_INTERRUPTED}[outcome]
