"""The ``go2-wbc`` command line: an action client that drives a simulated GO2."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import gc
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, NoReturn

import numpy as np

# actions/ and wbc/ never import mujoco, and these sim/ modules import it only when used,
# so all of them are safe before MUJOCO_GL is chosen.
from actions.go2.go2_actions import (
    FOLLOW_JOINT_TRAJECTORY_ACTION,
    HIGH_FIVE_ACTION,
    SIT_ACTION,
    STAND_ACTION,
)
from actions.go2.high_five_behaviour import MAX_HOLD_S
from actions.go2.pose_behaviour import MAX_DURATION_S, MIN_DURATION_S
from actions.messages import FollowJointTrajectoryGoal, HighFiveGoal, SitGoal, StandGoal
from actions.robot.robot_interface import STATE_SOURCES
from sim.cli_trajectory_file import load_trajectory_goal
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS, Plant
from sim.run_recorder import RAISED_LEG, MetricsHook, TickRecorder, write_plot
from sim.scene_overlay import DEFAULT_OVERLAYS, SceneOverlay, parse_overlays
from sim.sensor_faults import FAULT_KINDS, SensorFault
from sim.sensors import DEFAULT_SENSORS, SENSOR_PRESETS, SensorModel
from sim.video_recorder import VideoRecorder, choose_offscreen_gl
from sim.viewer import Pacer, ViewerHook, window_problem
from wbc.core.errors import ConfigurationError, WbcError
from wbc.estimation.estimators import DEFAULT_ESTIMATOR, ESTIMATORS, make_estimator
from wbc.model.description import LEGS
from wbc.motions.leg_lift import MAX_HEIGHT_M, MIN_HEIGHT_M

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from sim.control_loop import ControlLoop
    from sim.disturbances import PushSchedule
    from wbc.controller.control_output import ControlOutput

#: Exit codes.
EXIT_SUCCEEDED, EXIT_NOT_SUCCEEDED, EXIT_USAGE, EXIT_REJECTED, EXIT_UNAVAILABLE = 0, 1, 2, 3, 4
EXIT_INTERRUPTED = 130

#: Sim time [s] between refreshes of the progress line on a terminal.
PROGRESS_REFRESH_S = 0.25
#: Sim time [s] a goal may run beyond its expected duration before the CLI gives up on it.
GOAL_SLACK_S = 30.0
#: Sim time [s] the robot stands before the goal is sent. The plant is spawned at the pose
#: without contact forces; its feet settle (and slide ~3 mm) in the first 20 ms.
SETTLE_S = 0.3

EXIT_CODES_HELP = """\
exit status:
    0  the goal SUCCEEDED
    1  the goal ended CANCELED or ABORTED (or did not end in time)
    2  bad arguments, an action that is not served included (the message names the
       argument and what is valid)
    3  the action server rejected the goal (the reason is printed)
    4  cannot run here (no offscreen rendering for --video, a MUJOCO_GL MuJoCo rejects)
  130  interrupted: Ctrl-C cancels the goal and waits for the robot to unwind
"""

EXAMPLES_HELP = """\
examples:
  go2-wbc high-five                         # 0.40 m, hold 2 s, headless
  go2-wbc high-five --height 0.3 --hold 0 --metrics
  go2-wbc high-five --video hf.mp4 --plot hf.png --report hf.json --log hf.npz
  go2-wbc high-five --viewer --overlay all  # CoM, support polygon, forces, foot target
  go2-wbc high-five --push 40,0.1 --push-at 3 --push-dir 90
  go2-wbc high-five --cancel-at 2.5         # ends CANCELED with the foot down
  go2-wbc stand; go2-wbc sit --duration 1.5
  go2-wbc trajectory wave.yaml              # format: go2-wbc trajectory --help
  go2-wbc high-five --plant identified --plant-param calf_friction_loss=1.4
  go2-wbc high-five --control-rate 500      # the GO2's usual low-level rate

"""

TRAJECTORY_FORMAT_HELP = """\
trajectory file (YAML, or JSON with a .json suffix; same keys):
  joint_names: [FR_hip_joint, FR_thigh_joint, FR_calf_joint]   # joints of one leg
  points:                              # in time order
    - positions: [-0.1, -0.3, -1.6]    # [rad], one per joint name: foot up, in front
      velocities: [0.0, 0.0, 0.0]      # optional [rad/s]; in every point or in none
      accelerations: [0.0, 0.0, 0.0]   # optional [rad/s^2]; in every point or in none
      time_from_start: 2.0             # [s] from the moment the leg is free
  path_tolerance:                      # optional, per joint, during the motion
    - {name: FR_thigh_joint, position: 0.2}        # [rad]; 0 = server default, -1 = none
  goal_tolerance:                      # optional, per joint, at the end
    - {name: FR_thigh_joint, position: 0.02, velocity: 0.1}   # [rad], [rad/s]
  goal_time_tolerance: 0.5             # optional [s] after the last point
A file that cannot be read or does not have this shape is a usage error (exit 2);
joint names, lengths and times are judged by the action server (a rejection is exit 3).
The progress is the trajectory time reached: 'starting' while the leg is released (the body
shifts, the foot unloads), 'following', then 'settling' past the last point's time. The goal
ends with the foot up, the leg holding where it stopped, the robot on three feet; a Stand
goal puts the foot down.

"""


# --------------------------------------------------------------------------- argument types


def _number(text: str, expected: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return value


def _float_in(low: float, high: float, *, what: str, unit: str, fmt: str = ".2f"
              ) -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]``; the message says the range."""
    expected = f"{what} in [{low:{fmt}}, {high:{fmt}}] {unit}".rstrip()

    def parse(text: str) -> float:
        value = _number(text, expected)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text}")
        return value

    return parse


def _whole_in(low: int, high: int, *, what: str) -> Callable[[str], int]:
    """An argparse type: an integer in ``[low, high]``."""
    expected = f"{what} in [{low}, {high}]"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text}")
        return value

    return parse


def _push(text: str) -> tuple[float, float]:
    """``FORCE_N,DURATION_S`` as ``(force [N], duration [s])``; the push is built with its time
    and direction, once all the options are known."""
    expected = "FORCE_N,DURATION_S with a force in [0, 500] N and a duration in (0, 5] s"
    parts = text.split(",")
    try:
        force, duration = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected {expected} (e.g. 40,0.1), received {text!r}") from None
    if not (0.0 <= force <= 500.0 and 0.0 < duration <= 5.0):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return force, duration


def _video_size(text: str) -> tuple[int, int]:
    expected = "WIDTHxHEIGHT in pixels, both even and in [16, 3840] (e.g. 640x480)"
    try:
        width, height = (int(p) for p in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
    if not all(16 <= n <= 3840 and n % 2 == 0 for n in (width, height)):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return width, height


def _overlays(text: str) -> tuple[str, ...]:
    try:
        return parse_overlays(text)
    except ConfigurationError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _output(*suffixes: str) -> Callable[[str], Path]:
    """An argparse type: a file path with one of ``suffixes`` in an existing directory."""
    def parse(text: str) -> Path:
        path = Path(text)
        if path.suffix.lower() not in suffixes:
            raise argparse.ArgumentTypeError(
                f"expected a file name ending in {' or '.join(suffixes)}, received {text!r}")
        if not path.parent.is_dir():
            raise argparse.ArgumentTypeError(
                f"directory {str(path.parent)!r} does not exist (for {text!r})")
        return path

    return parse


def _trajectory_file(text: str) -> FollowJointTrajectoryGoal:
    try:
        return load_trajectory_goal(Path(text))
    except OSError as err:
        raise argparse.ArgumentTypeError(
            f"cannot read {text!r}: {err.strerror or err}") from None
    except (ValueError, ConfigurationError) as err:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a valid trajectory file: {err}") from None


# --------------------------------------------------------------------------- the parser


class _Parser(argparse.ArgumentParser):
    """Reports a usage error on one line, naming the option: ``--height: expected ...``."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def _plant_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of a plant parameter, checked by the plant itself (name and range).

    The value is a number, three comma-separated numbers for ``payload_offset_m`` or a word
    for ``cone``; anything else is handed over as text, so that the plant's message says
    what it expected.
    """
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    value: Any = value_text
    if name != "cone":
        parts = tuple(_number_or_text(v) for v in value_text.split(","))
        value = parts if len(parts) > 1 else parts[0]
        if name == "condim" and isinstance(value, float) and value.is_integer():
            value = int(value)
    try:
        # The ranges do not depend on the preset, so any plant checks them.
        Plant().with_params(**{name: value})
    except WbcError as err:
        message = str(err)
        if name.startswith("joint_"):  # reported for the first joint type: name the option's
            message = f"{name}:{message.partition(':')[2]}"
        raise argparse.ArgumentTypeError(message) from None
    return name, value


def _sensor_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of a sensor-model parameter, checked by the model (name and range)."""
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    value: Any = _number_or_text(value_text)
    if name == "foot_force_integer":
        words = {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}
        value = words.get(value_text.strip().lower(), value_text)
    try:
        SensorModel().with_params(**{name: value})
    except WbcError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return name, value


def _estimator_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of an estimator parameter; checked once the estimator is known."""
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    words = {"true": True, "yes": True, "false": False, "no": False}
    value = words.get(value_text.strip().lower(), _number_or_text(value_text))
    return name, value


def _sensor_fault(text: str) -> SensorFault:
    """``KIND,AT_S,DURATION_S[,NAME]``: a sensor fault on the simulated clock."""
    parts = [p.strip() for p in text.split(",")]
    expected = (f"KIND,AT_S,DURATION_S[,FOOT_OR_JOINT] with KIND one of "
                f"{', '.join(FAULT_KINDS)} (e.g. dropout,3.5,0.02 or foot_zero,1,5,RL)")
    if len(parts) not in (3, 4):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    try:
        at_s, duration_s = float(parts[1]), float(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
    try:
        return SensorFault(parts[0], at_s, duration_s, parts[3] if len(parts) == 4 else "")
    except WbcError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _number_or_text(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text


def _plant_options(group: Any) -> None:
    """The simulated plant and the control and physics rates, added to ``group``."""
    group.add_argument("--plant", choices=tuple(PLANT_PRESETS), default=DEFAULT_PLANT,
                       help="the simulated GO2's joints and contacts, which the controller "
                            f"does not know (default: {DEFAULT_PLANT}; 'ideal' matches the "
                            "controller's model)")
    group.add_argument("--plant-param", type=_plant_param, action="append", default=[],
                       metavar="NAME=VALUE",
                       help="change one plant parameter, repeatable: joint_damping, "
                            "joint_friction_loss, joint_armature (every joint), hip_/thigh_/"
                            "calf_ + damping/friction_loss/armature (one joint type), "
                            "foot_friction, torsional_friction, rolling_friction, condim, "
                            "cone=elliptic|pyramidal, impratio, foot_radius_m, payload_kg, "
                            "payload_offset_m=X,Y,Z (default: the preset's values)")
    group.add_argument("--control-rate", type=_float_in(10.0, 10000.0, what="a rate",
                                                        unit="Hz", fmt="g"),
                       default=1000.0, metavar="HZ",
                       help="control rate [Hz] (default: 1000; the GO2's usual is 500)")
    group.add_argument("--physics-dt", type=_float_in(1e-5, 0.01, what="a timestep",
                                                      unit="s", fmt="g"),
                       default=None, metavar="SECONDS",
                       help="physics timestep [s]; a whole number of them per control period "
                            "(default: 0.001, or the control period if shorter)")


def _state_options(group: Any) -> None:
    """Where the controller's state comes from, the sensors, a command delay and faults."""
    group.add_argument("--state", choices=STATE_SOURCES, default="estimate",
                       help="the controller's state: 'estimate' (default: the state estimator "
                            "on the simulated sensors, as on a real GO2) or 'truth' (the "
                            "simulator's exact state, for comparison)")
    group.add_argument("--estimator", choices=tuple(ESTIMATORS), default=DEFAULT_ESTIMATOR,
                       help="the state estimator: " + "; ".join(
                           f"'{name}': {what}" for name, what in ESTIMATORS.items())
                       + f" (default: {DEFAULT_ESTIMATOR}; see the README's State estimation)")
    group.add_argument("--estimator-param", type=_estimator_param, action="append", default=[],
                       metavar="NAME=VALUE",
                       help="change one estimator parameter, repeatable: use_foot_force=false "
                            "(contact from the schedule alone: a robot without foot sensors), "
                            "trust_timeout_s, foot_force_on, foot_force_off, ... (default: the "
                            "estimator's values)")
    group.add_argument("--sensors", choices=tuple(SENSOR_PRESETS), default=DEFAULT_SENSORS,
                       help=f"what the simulated GO2 measures (default: {DEFAULT_SENSORS}: its "
                            "IMU, encoders and foot sensors with noise and biases; 'exact': "
                            "no noise)")
    group.add_argument("--sensor-param", type=_sensor_param, action="append", default=[],
                       metavar="NAME=VALUE",
                       help="change one sensor parameter, repeatable: gyro_noise_rad_s, "
                            "gyro_bias_rad_s, accel_noise_m_s2, accel_bias_m_s2, "
                            "attitude_time_constant_s, joint_position_noise_rad, "
                            "joint_velocity_noise_rad_s, foot_force_gain, ... (default: the "
                            "preset's values)")
    group.add_argument("--sensor-seed", type=_whole_in(0, 2**31 - 1, what="a seed"), default=0,
                       metavar="N", help="seed of the sensors' noise and biases (default: 0)")
    group.add_argument("--sensor-fault", type=_sensor_fault, action="append", default=[],
                       metavar="KIND,AT_S,DURATION_S[,NAME]",
                       help="a sensor fault from sim time AT_S for DURATION_S, repeatable; "
                            f"KIND: {', '.join(FAULT_KINDS)}; NAME: the foot of a foot fault "
                            "(default FR) or the joint of joint_nan (default FR_thigh_joint)")
    group.add_argument("--command-delay", type=_float_in(0.0, 0.1, what="a delay", unit="s",
                                                         fmt="g"),
                       default=0.0, metavar="SECONDS",
                       help="time [s] between a command and the motor drivers applying it, a "
                            "whole number of control periods (default: 0; legged_control "
                            "simulates a Unitree robot with 0.009)")


def _resolve_plant(args: argparse.Namespace) -> None:
    """Build ``args.plant_model`` (and the sensor model) and check the rates and the delay;
    a usage error names the option.

    Imports MuJoCo: a ``--video`` run chooses its rendering backend before this.
    """
    try:
        args.plant_model = Plant.preset(args.plant).with_params(**dict(args.plant_param))
    except WbcError as err:
        args.parser.error(f"--plant-param: {err}")
    if hasattr(args, "sensors"):
        try:
            args.sensor_model = SensorModel.preset(args.sensors).with_params(
                **dict(args.sensor_param))
        except WbcError as err:
            args.parser.error(f"--sensor-param: {err}")
    from sim.control_loop import PHYSICS_TIMESTEP_S
    from sim.mujoco_robot import physics_steps_per_period

    args.control_period_s = 1.0 / args.control_rate
    if args.physics_dt is None:
        args.physics_dt = min(PHYSICS_TIMESTEP_S, args.control_period_s)
    try:
        args.physics_steps = physics_steps_per_period(args.control_period_s, args.physics_dt)
    except WbcError as err:
        args.parser.error(f"--control-rate: {args.control_rate:g} Hz with --physics-dt "
                          f"{args.physics_dt:g} s: {err}")
    if hasattr(args, "estimator_param"):
        try:
            make_estimator(args.estimator, control_period_s=args.control_period_s,
                           **dict(args.estimator_param))
        except WbcError as err:
            args.parser.error(f"--estimator-param: {err}")
    if hasattr(args, "command_delay"):
        ticks = round(args.command_delay / args.control_period_s)
        if abs(ticks * args.control_period_s - args.command_delay) > 1e-9:
            args.parser.error(
                f"--command-delay: expected a whole number of control periods of "
                f"{args.control_period_s:g} s (e.g. {args.control_period_s:g}, "
                f"{9 * args.control_period_s:g}), received {args.command_delay:g}")
        args.command_delay_ticks = int(ticks)


@contextlib.contextmanager
def startup_objects_frozen() -> Iterator[None]:
    """Keep what start-up allocated out of the garbage collector's scans while the loop runs.

    Building the loop leaves about 150,000 objects (the models, MuJoCo, numba's compiled
    code); a full collection of them takes about 20 ms, twenty control periods if it came
    inside a tick. The loop's ticks free what they allocate, so full collections are rare,
    but a long run gets one. ``gc.freeze()`` moves them all to a generation no collection
    scans; ``gc.unfreeze()`` gives them back when the block ends (the command line may run
    inside a longer-lived Python process). Do the same around your own loop.
    """
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def _plant_line(args: argparse.Namespace) -> str:
    line = (f"{args.plant_model.describe()}; control {args.control_rate:g} Hz, physics "
            f"{args.physics_dt * 1e3:g} ms")
    if getattr(args, "command_delay_ticks", 0):
        line += f"; commands applied {args.command_delay * 1e3:g} ms late"
    return line


def state_line(args: argparse.Namespace) -> str:
    """The first line a run prints: where the controller's state comes from, which sensors."""
    if args.state == "truth":
        return ("state: the simulator's exact state (--state truth; a GO2 measures no base "
                f"position or velocity); {args.sensor_model.describe()} unused")
    faults = "".join(f"; fault: {fault.describe()}" for fault in args.sensor_fault)
    changed = "".join(f", {name}={value}" for name, value in args.estimator_param)
    return (f"state: estimated ({args.estimator}, {ESTIMATORS[args.estimator]}{changed}) from "
            f"{args.sensor_model.describe()}, seed {args.sensor_seed}{faults}")


def simulated_loop(args: argparse.Namespace, pose: str = "standing") -> "ControlLoop":
    """The loop a goal-sending command runs: plant, rates, sensors, state source, delay,
    faults from the options."""
    from sim.control_loop import ControlLoop

    return ControlLoop.simulated(
        pose=pose, plant=args.plant_model, control_period_s=args.control_period_s,
        physics_timestep_s=args.physics_dt, sensors=args.sensor_model,
        sensor_seed=args.sensor_seed, state=args.state,
        estimator=(make_estimator(args.estimator, control_period_s=args.control_period_s,
                                  **dict(args.estimator_param))
                   if args.state == "estimate" else None),
        command_delay_ticks=args.command_delay_ticks, sensor_faults=args.sensor_fault)


def _run_options() -> argparse.ArgumentParser:
    """Options shared by every goal-sending subcommand."""
    common = _Parser(add_help=False)
    run = common.add_argument_group("simulation")
    _plant_options(run)
    _state_options(run)
    sim_time = _float_in(0.0, 3600.0, what="a sim time", unit="s", fmt="g")
    run.add_argument("--realtime", action="store_true",
                     help="pace the simulation to the wall clock (default: as fast as possible)")
    run.add_argument("--viewer", action="store_true",
                     help="open the MuJoCo viewer (implies --realtime); it stays open on "
                          "the final state until you close it (see --viewer-exit); without a "
                          "display ($DISPLAY or $WAYLAND_DISPLAY) it says so and runs headless "
                          "(default: headless)")
    run.add_argument("--viewer-exit", action="store_true",
                     help="with --viewer: close the window when the goal ends (default: the "
                          "window stays open on the final state, the simulation paused, "
                          "until you close it)")
    run.add_argument("--start-pose", choices=("standing", "lying"), default=None,
                     help="pose the robot starts in (default: lying for 'stand', "
                          "standing otherwise)")
    run.add_argument("--cancel-at", type=sim_time, metavar="SECONDS",
                     help="cancel the goal at this simulated time [s]; the robot stands "
                          f"{SETTLE_S:g} s before the goal is sent (default: never)")
    run.add_argument("--push", type=_push, metavar="FORCE_N,DURATION_S",
                     help="push the base horizontally with FORCE_N [N] for DURATION_S [s] "
                          "(default: no push)")
    run.add_argument("--push-at", type=sim_time, metavar="SECONDS",
                     help="simulated time [s] the push starts (default: 3.5, during the "
                          "hold of a high five; goals are sent at 0.3 s)")
    run.add_argument("--push-dir", type=_float_in(-360.0, 360.0, what="an angle", unit="deg",
                                                  fmt="g"),
                     metavar="DEGREES",
                     help="push direction [deg] relative to the robot's heading: 0 forward, "
                          "90 left, 180 backward, 270 right (default: 90)")
    out = common.add_argument_group("outputs")
    out.add_argument("--metrics", action="store_true",
                     help="measure the run (raised-foot tracking, stance sliding, CoM margin, "
                          "tilt, torques, QP failures, tick times) and print a summary; "
                          "implied by --report (default: off: measuring takes about as long "
                          "as controlling)")
    out.add_argument("--video", type=_output(".mp4"), metavar="FILE.mp4",
                     help="record an MP4 from a camera tracking the robot, rendered offscreen "
                          "(works without a display or GPU; default: none)")
    out.add_argument("--fps", type=_whole_in(1, 240, what="frames per second"), default=None,
                     metavar="N", help="video frame rate [1/s] of simulated time (default: 30)")
    out.add_argument("--video-size", type=_video_size, default=None, metavar="WxH",
                     help="video frame size in pixels (default: 640x480)")
    out.add_argument("--overlay", type=_overlays, default=None, metavar="LIST",
                     help="what the viewer and the video draw over the robot, comma-separated: "
                          "com (the centre of mass and its ground projection), polygon (the "
                          "support polygon of the loaded feet, its margin inside), forces (the "
                          "commanded contact forces), measured (MuJoCo's contact forces), "
                          "target (the raised foot's target and its trace); or all, or none "
                          f"(default: {','.join(DEFAULT_OVERLAYS)})")
    out.add_argument("--plot", type=_output(".png", ".pdf", ".svg"), metavar="FILE.png",
                     help="plot raised-foot height vs target, CoM margin to the support edge, "
                          "FR normal force, the state estimate's height and velocity errors "
                          "and control tick time against sim time "
                          "(default: none)")
    out.add_argument("--report", type=_output(".json"), metavar="FILE.json",
                     help="write the result, the feedback with sim times and the run metrics "
                          "(default: none)")
    out.add_argument("--log", type=_output(".npz"), metavar="FILE.npz",
                     help="write per-tick arrays: t_s, q, v (the controller's state, "
                          "Pinocchio convention, joint_names beside), q_true, v_true (the "
                          "simulator's exact state), estimate_contact, estimate_flags, tau, "
                          "raised-foot target and position, phase, "
                          "MuJoCo foot contact forces (4x3), CoM margin, QP status, tick time "
                          "(default: none)")
    return common


def build_parser() -> argparse.ArgumentParser:
    """The ``go2-wbc`` argument parser."""
    parser = _Parser(
        prog="go2-wbc",
        description="Send an action goal to a simulated Unitree GO2 under whole-body\n"
                    "control and print its feedback and result, like a ROS 2 action client.",
        epilog=EXAMPLES_HELP + EXIT_CODES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    common = _run_options()

    def add(name: str, help_text: str, epilog: str = "") -> argparse.ArgumentParser:
        command = sub.add_parser(name, parents=[common], help=help_text,
                                 description=help_text, epilog=epilog + EXIT_CODES_HELP,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
        command.set_defaults(parser=command)
        return command

    high_five = add(HIGH_FIVE_ACTION.replace("_", "-"),
                    "raise the front-right foot, hold it up, put it back down")
    high_five.add_argument(
        "--height", type=_float_in(MIN_HEIGHT_M, MAX_HEIGHT_M, what="a height", unit="m"),
        default=0.40, metavar="M",
        help=f"foot height above the ground [m], in [{MIN_HEIGHT_M:.2f}, {MAX_HEIGHT_M:.2f}] "
             "(default: 0.40)")
    high_five.add_argument(
        "--hold", type=_whole_in(0, MAX_HOLD_S, what="a whole number of seconds"), default=2,
        metavar="S",
        help=f"seconds to hold the foot up [s], a whole number in [0, {MAX_HOLD_S}] "
             "(default: 2)")
    high_five.set_defaults(run=_high_five)

    duration = _float_in(MIN_DURATION_S, MAX_DURATION_S, what="a duration", unit="s", fmt="g")
    for name, verb, run in ((STAND_ACTION, "rise to the standing pose", _stand),
                            (SIT_ACTION, "lower the body to the lying pose", _sit)):
        pose = add(name, f"{verb} on four feet")
        pose.add_argument("--duration", type=duration, default=2.0, metavar="S",
                          help=f"time to reach the pose [s], in [{MIN_DURATION_S:g}, "
                               f"{MAX_DURATION_S:g}] (default: 2.0)")
        pose.set_defaults(run=run)

    trajectory = add("trajectory", "follow a joint trajectory read from a YAML or JSON file "
                     "(FollowJointTrajectory)", TRAJECTORY_FORMAT_HELP)
    trajectory.add_argument("file", type=_trajectory_file, metavar="FILE",
                            help="the trajectory file (format below)")
    trajectory.set_defaults(run=_trajectory)

    stand_pd = sub.add_parser("stand-pd", help="stand under a joint PD (baseline, no QP)",
                              description="Stand under a joint PD with gravity compensation "
                                          "(the baseline without the QP); print the drift.")
    stand_pd.add_argument("--duration", type=_float_in(0.001, 60.0, what="a duration", unit="s",
                                                       fmt="g"),
                          default=3.0, metavar="S",
                          help="simulated seconds [s], in [0.001, 60] (default: 3.0)")
    _plant_options(stand_pd.add_argument_group("simulation"))
    stand_pd.set_defaults(run=_stand_pd, parser=stand_pd)
    from sim.action_cli import add_action_commands  # it imports this module's helpers

    add_action_commands(sub)
    return parser


def _check_combinations(args: argparse.Namespace) -> None:
    """Options that only make sense with another one; the plant and the rates."""
    if getattr(args, "video", None) is not None:
        choose_offscreen_gl()  # before _resolve_plant imports MuJoCo, which reads MUJOCO_GL
    _resolve_plant(args)
    if not hasattr(args, "video"):
        return
    for option, needs in (("fps", "video"), ("video_size", "video"),
                          ("push_at", "push"), ("push_dir", "push")):
        if getattr(args, option) is not None and getattr(args, needs) is None:
            args.parser.error(f"--{option.replace('_', '-')}: only used with --{needs}")
    if args.overlay is not None and args.video is None and not args.viewer:
        args.parser.error("--overlay: only used with --video or --viewer")
    if args.viewer_exit and not args.viewer:
        args.parser.error("--viewer-exit: only used with --viewer")
    args.overlay = DEFAULT_OVERLAYS if args.overlay is None else args.overlay
    args.fps = args.fps or 30
    args.video_size = args.video_size or (640, 480)
    args.push_at = 3.5 if args.push_at is None else args.push_at
    args.push_dir = 90.0 if args.push_dir is None else args.push_dir


# --------------------------------------------------------------------------- subcommands


def _high_five(args: argparse.Namespace) -> int:
    goal = HighFiveGoal(target_height=args.height, hold_seconds=args.hold)
    return GoalRun(args, HIGH_FIVE_ACTION, goal,
                   f"target_height {goal.target_height:.2f} m, hold {goal.hold_seconds} s",
                   expected_s=goal.hold_seconds + 8.0).run()


def _stand(args: argparse.Namespace) -> int:
    args.start_pose = args.start_pose or "lying"
    goal = StandGoal(duration_s=args.duration)
    return GoalRun(args, STAND_ACTION, goal, f"duration {goal.duration_s:g} s",
                   expected_s=goal.duration_s).run()


def _sit(args: argparse.Namespace) -> int:
    goal = SitGoal(duration_s=args.duration)
    return GoalRun(args, SIT_ACTION, goal, f"duration {goal.duration_s:g} s",
                   expected_s=goal.duration_s).run()


def _trajectory(args: argparse.Namespace) -> int:
    goal: FollowJointTrajectoryGoal = args.file
    points = goal.trajectory.points
    end_s = points[-1].time_from_start.to_seconds() if points else 0.0
    what = (f"{len(goal.trajectory.joint_names)} joint(s), {len(points)} point(s), "
            f"{end_s:g} s")
    names = goal.trajectory.joint_names
    leg = names[0].split("_")[0] if names and names[0].split("_")[0] in LEGS else RAISED_LEG
    return GoalRun(args, FOLLOW_JOINT_TRAJECTORY_ACTION, goal, what,
                   expected_s=end_s + goal.goal_time_tolerance.to_seconds() + 3.0,
                   trajectory_end_s=end_s, leg=leg).run()


def _stand_pd(args: argparse.Namespace) -> int:
    from sim.simulator import Go2Simulator
    from wbc.controller.joint_pd_controller import JointPdController

    print(_plant_line(args))
    sim = Go2Simulator(plant=args.plant_model, timestep_s=args.physics_dt)
    controller = JointPdController(sim.description.pose("standing"))
    z0 = sim.state()[0][2]
    # One torque per control period, held over its physics steps (as a driver would).
    for _ in range(max(1, round(args.duration / args.control_period_s))):
        sim.step(controller.compute(*sim.state()), args.physics_steps)
    q, _ = sim.state()
    forces = sim.foot_contact_forces()
    print(f"stood {sim.time_s:.2f} s under a joint PD with gravity compensation")
    print(f"base height {z0:.4f} m -> {q[2]:.4f} m; drift {np.linalg.norm(q[:2]) * 1e3:.2f} mm")
    print("foot normal forces [N]: " + ", ".join(f"{k} {v[2]:.1f}" for k, v in forces.items()))
    return EXIT_SUCCEEDED


# --------------------------------------------------------------------------- printing


def _feedback_view(feedback: Any, trajectory_end_s: float | None
                   ) -> tuple[str, float, float | None]:
    """``(phase, progress 0..1, largest joint error [rad] or None)`` of a feedback message."""
    if hasattr(feedback, "phase"):
        return feedback.phase, float(feedback.progress), None
    # FollowJointTrajectory feedback has no phase field: the phase shown and the progress
    # are read from the trajectory time reached, desired.time_from_start.
    desired_s = feedback.desired.time_from_start.to_seconds()
    progress = min(1.0, desired_s / trajectory_end_s) if trajectory_end_s else 1.0
    error = max((abs(e) for e in feedback.error.positions), default=0.0)
    if desired_s <= 0.0:
        phase = "starting"  # the leg is being released, or the start stamp is ahead
    elif trajectory_end_s is None or desired_s <= trajectory_end_s:
        phase = "following"
    else:
        phase = "settling"  # past the last point's time: the goal tolerance is checked
    return phase, progress, error


class FeedbackPrinter:
    """Prints feedback: one line per phase, plus a refreshed progress line on a terminal."""

    def __init__(self, stream: IO[str], *, tty: bool):
        self.stream = stream
        self.tty = tty
        self.phase = ""
        self._shown_s = -math.inf
        self._progress_line = False

    def feedback(self, now_s: float, phase: str, progress: float, detail: str) -> None:
        """Show one feedback message received at sim time ``now_s`` [s]."""
        text = f"[{now_s:7.3f} s] {100 * progress:4.0f} %  {phase}"
        if detail:
            text += f"  ({detail})"
        if phase != self.phase:
            self.phase = phase
            self.line(text)
        elif self.tty and now_s - self._shown_s >= PROGRESS_REFRESH_S - 1e-9:
            bar = "#" * round(20 * progress)
            self.stream.write(f"\r\033[K{text}  [{bar:<20}]")
            self.stream.flush()
            self._progress_line = True
        else:
            return
        self._shown_s = now_s

    def line(self, text: str) -> None:
        """Print a line, replacing the progress line if one is showing."""
        if self._progress_line:
            self.stream.write("\r\033[K")
            self._progress_line = False
        self.stream.write(text + "\n")
        self.stream.flush()


class _Timed:
    """Wraps a hook and adds the wall time it takes to ``totals[0]``."""

    def __init__(self, hook: Callable[[ControlLoop, ControlOutput], None], totals: list[float]):
        self.hook, self.totals = hook, totals

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        start = time.perf_counter()
        self.hook(loop, out)
        self.totals[0] += time.perf_counter() - start


# --------------------------------------------------------------------------- one goal


@dataclass
class _Event:
    t_s: float
    event: str
    details: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {"t_s": round(self.t_s, 4), "event": self.event, **self.details}


class GoalRun:
    """Sends one goal to a fresh simulated GO2, spins until it ends, writes the outputs.

    Args:
        args: The parsed options (outputs, pushes, cancel time, pacing).
        action_name: The action server to send the goal to.
        goal: The goal message.
        goal_text: How to print the goal.
        expected_s: How long the goal should take [s] (the CLI gives up
            :data:`GOAL_SLACK_S` later).
        trajectory_end_s: Time of a trajectory's last point [s] (its feedback's progress).
        leg: The leg whose foot is plotted and logged (the one that moves).
        stream: Where to print (standard output by default).
    """

    def __init__(self, args: argparse.Namespace, action_name: str, goal: Any, goal_text: str,
                 *, expected_s: float, trajectory_end_s: float | None = None,
                 leg: str = RAISED_LEG, stream: IO[str] | None = None):
        self.args = args
        self.action_name = action_name
        self.goal = goal
        self.goal_text = goal_text
        self.deadline_s = expected_s + GOAL_SLACK_S
        self.trajectory_end_s = trajectory_end_s
        self.leg = leg
        self.stream = stream or sys.stdout
        self.printer = FeedbackPrinter(self.stream, tty=self.stream.isatty())
        self.phase = ""
        self.progress = 0.0
        self.max_error = 0.0
        self.feedback: list[dict[str, Any]] = []
        self.events: list[_Event] = []
        self.handle: ClientGoalHandle | None = None
        #: Wall time [s] spent measuring, recording, rendering, in the viewer and sleeping:
        #: left out of the real-time factor, which is that of simulation and control.
        self.overhead_s = [0.0]
        self.result: dict[str, Any] | None = None
        self.summary: Any = None
        self.recorder: TickRecorder | None = None
        self.video: VideoRecorder | None = None
        self.pushes: PushSchedule | None = None
        self.wall_start = time.perf_counter()
        self.wall_s = 0.0

    def say(self, text: str) -> None:
        """One line of output (replacing the progress line)."""
        self.printer.line(text)

    def run(self) -> int:
        """Run the goal; return the exit code."""
        args = self.args
        problem = window_problem() if args.viewer else ""
        viewer = args.viewer and not problem
        if problem:
            print(f"go2-wbc: --viewer: {problem}; running headless", file=sys.stderr)
        self.say(state_line(args))
        self.say(_plant_line(args))
        loop = simulated_loop(args, args.start_pose or "standing")
        with startup_objects_frozen():
            return self._run(loop, viewer)

    def _run(self, loop: ControlLoop, viewer: bool) -> int:
        from sim.disturbances import Push, PushSchedule

        args = self.args
        if args.push is not None:
            force_n, duration_s = args.push
            self.pushes = PushSchedule(loop.sim, [Push(
                at_s=args.push_at, force_n=force_n, duration_s=duration_s,
                direction_deg=args.push_dir, relative_to_heading=True)])
        loop.spin_for(SETTLE_S)
        if self.action_name not in loop.runner.server_names:
            print(f"go2-wbc: the '{self.action_name}' action is not served by this version "
                  f"(served: {', '.join(loop.runner.server_names)})", file=sys.stderr)
            return EXIT_UNAVAILABLE
        closers: list[Callable[[], None]] = []
        self.view: ViewerHook | None = None
        self.pacer: Pacer | None = None
        try:
            try:
                code = self._attach_hooks(loop, viewer, closers)
                if code is None:
                    code = self._spin(loop)
            finally:
                for close in closers:
                    close()
            self._write_outputs()
            self._keep_viewer_open(loop, code)
        finally:
            if self.view is not None:  # after the outputs: the window outlives the run
                self.view.close()
        return code

    def _attach_hooks(self, loop: ControlLoop, viewer: bool,
                      closers: list[Callable[[], None]]) -> int | None:
        args = self.args
        self.metrics = None
        if args.metrics or args.report is not None:
            self.metrics = MetricsHook(loop, lambda: self.phase, self.leg)
            loop.hooks.append(_Timed(self.metrics, self.overhead_s))
        if args.log or args.plot:
            self.recorder = TickRecorder(lambda: self.phase, self.leg, loop)
            loop.hooks.append(_Timed(self.recorder, self.overhead_s))
        overlay = (SceneOverlay(args.overlay, status_of=lambda: (self.phase, self.progress))
                   if args.overlay else None)
        if args.video is not None:
            try:
                video = VideoRecorder(loop.sim, args.video, fps=args.fps, size=args.video_size,
                                      overlay=overlay)
            except Exception as err:  # noqa: BLE001 - GL backends fail in assorted types
                print(f"go2-wbc: --video: offscreen rendering is unavailable "
                      f"(MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}): "
                      f"{' '.join(str(err).split())}. Install libosmesa6 "
                      "(apt-get install libosmesa6) or set MUJOCO_GL=egl", file=sys.stderr)
                return EXIT_UNAVAILABLE
            closers.append(video.close)
            loop.hooks.append(_Timed(video, self.overhead_s))
            self.video = video
        if viewer:
            try:
                view = ViewerHook(loop.sim, overlay=overlay, on_closed=self._viewer_closed)
            except Exception as err:  # noqa: BLE001 - GLFW and X fail in assorted types
                print(f"go2-wbc: --viewer: cannot open a window ({' '.join(str(err).split())}); "
                      "running headless", file=sys.stderr)
            else:
                self.view = view  # closed by _run, after the outputs
                loop.hooks.append(_Timed(view, self.overhead_s))
        if args.realtime or viewer:
            self.pacer = Pacer(loop.sim)
            loop.hooks.append(_Timed(self.pacer, self.overhead_s))
        return None

    def _viewer_closed(self) -> None:
        """The viewer's window went mid-run: say so; the run goes on, unpaced unless
        --realtime asked for the wall clock's pace."""
        view = self.view
        if view is None:
            return
        unpaced = False
        if self.pacer is not None and not self.args.realtime:
            self.pacer.active, unpaced = False, True
        how = ("was closed" if view.error is None else
               f"failed ({type(view.error).__name__}: {' '.join(str(view.error).split())})")
        self.say(f"[{view.closed_at_s:7.3f} s] viewer: the window {how}; the run goes on "
                 f"headless{', as fast as possible' if unpaced else ''}")

    def _keep_viewer_open(self, loop: ControlLoop, code: int) -> None:
        """--viewer: the window stays on the final state, paused, until its user closes it
        (not with --viewer-exit, after Ctrl-C, or when it has gone)."""
        view = self.view
        if (view is None or self.args.viewer_exit or code == EXIT_INTERRUPTED
                or not view.is_open):
            return
        self.say(f"[{loop.context.now_s:7.3f} s] viewer: paused on the final state; close the "
                 "window to exit (--viewer-exit closes it at the end)")
        with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C closes it too
            view.hold(loop)

    # -- the action client -----------------------------------------------------------------

    def _on_feedback(self, message: Any) -> None:
        now_s = self.loop.context.now_s
        phase, progress, error = _feedback_view(message.feedback, self.trajectory_end_s)
        self.phase, self.progress = phase, progress
        entry = {"t_s": round(now_s, 4), "phase": phase, "progress": round(progress, 4)}
        detail = ""
        if error is not None:
            entry["max_joint_error_rad"] = round(error, 5)
            self.max_error = max(self.max_error, error)
            if self.max_error > 0.0:
                detail = f"largest joint error so far {self.max_error:.4f} rad"
        self.feedback.append(entry)
        self.printer.feedback(now_s, phase, progress, detail)

    def _spin(self, loop: ControlLoop) -> int:
        self.loop = loop
        client = loop.client(self.action_name)
        self.say(f"[{loop.robot.time_s:7.3f} s] {self.action_name}: sending goal "
                 f"({self.goal_text})")
        self.wall_start = time.perf_counter()
        handle_future = client.send_goal_async(self.goal, feedback_callback=self._on_feedback)
        # Called in the tick that decides, before that tick's feedback.
        handle_future.add_done_callback(self._on_goal_response)
        try:
            while not handle_future.done():
                loop.spin_once()
            self.handle = handle = handle_future.result()
            if not handle.accepted:
                return EXIT_REJECTED
            result_future = handle.get_result_async()
            while not result_future.done():
                self._scheduled(loop, handle)
                loop.spin_once()
        except KeyboardInterrupt:
            return self._interrupted(loop)
        self.wall_s = time.perf_counter() - self.wall_start
        return self._finish(result_future.result())

    def _on_goal_response(self, future: Any) -> None:
        handle, now = future.result(), self.loop.context.now_s
        if handle.accepted:
            self._event("accepted")
            self.say(f"[{now:7.3f} s] goal accepted")
            return
        rejection = handle.rejection
        self.say(f"[{now:7.3f} s] goal rejected (code {rejection.code}): {rejection.message}")
        self.result = {"status": "REJECTED", "success": False, "message": rejection.message,
                       "rejection_code": rejection.code}

    def _scheduled(self, loop: ControlLoop, handle: ClientGoalHandle) -> None:
        """The cancel and the push, at their sim times; give up on a goal that overruns."""
        args, now = self.args, loop.robot.time_s
        if args.cancel_at is not None and now >= args.cancel_at - 1e-9 and not self._done(
                "cancel_requested"):
            self._cancel(handle, "cancel_requested", f"--cancel-at {args.cancel_at:g}")
        if self.pushes is not None:
            applied = len(self.pushes.applied)
            self.pushes(loop, loop.last_output)  # applies the push once it is due
            for t_s, push, force in self.pushes.applied[applied:]:
                self._event("push", t_s, force_n=[round(float(f), 3) for f in force],
                            duration_s=push.duration_s, direction_deg=push.direction_deg)
                self.say(f"[{t_s:7.3f} s] push: {push.force_n:g} N at {push.direction_deg:g} "
                         f"deg for {push.duration_s:g} s")
        if now > self.deadline_s and not self._done("timeout"):
            self._cancel(handle, "timeout", f"no result after {now:.1f} s of sim time")

    def _cancel(self, handle: ClientGoalHandle, event: str, reason: str) -> None:
        now = self.loop.robot.time_s  # the request is handled on the next tick, at this time
        self._event(event, now, reason=reason)
        self.say(f"[{now:7.3f} s] canceling the goal ({reason})")

        def replied(future: Any) -> None:
            response = future.result()
            self.say(f"[{self.loop.context.now_s:7.3f} s] cancel "
                     f"{'accepted' if response.accepted else 'refused'}: {response.message}")

        handle.cancel_goal_async().add_done_callback(replied)

    def _interrupted(self, loop: ControlLoop) -> int:
        """Ctrl-C: cancel the goal and let the robot unwind (a second Ctrl-C stops at once)."""
        if self.handle is None or not self.handle.accepted:
            return EXIT_INTERRUPTED
        self._cancel(self.handle, "interrupted", "Ctrl-C")
        result_future = self.handle.get_result_async()
        end = loop.robot.time_s + GOAL_SLACK_S
        while not result_future.done() and loop.robot.time_s < end:
            loop.spin_once()
        self.wall_s = time.perf_counter() - self.wall_start
        if result_future.done():
            self._finish(result_future.result())
        return EXIT_INTERRUPTED

    def _finish(self, wrapped: Any) -> int:
        result = wrapped.result
        error_code = getattr(result, "error_code", 0)
        success = bool(getattr(result, "success", error_code == 0))
        success = success and wrapped.status.name == "SUCCEEDED"
        message = getattr(result, "message", None) or getattr(result, "error_string", "")
        self.result = {"status": wrapped.status.name, "success": success, "message": message}
        if hasattr(result, "error_code"):
            self.result["error_code"] = error_code
        self._event("result", status=wrapped.status.name)
        text = f"[{self.loop.context.now_s:7.3f} s] result: {wrapped.status.name}"
        if hasattr(result, "error_code"):
            text += f" (error_code {error_code})"
        self.say(text + (f": {message}" if message else ""))
        if self.metrics is not None:
            self.summary = self.metrics.metrics.summary(
                max(self.wall_s - self.overhead_s[0], 1e-9))
            self.say(_metrics_text(self.summary, raised=self.action_name == HIGH_FIVE_ACTION,
                                   estimated=self.args.state == "estimate"))
        return EXIT_SUCCEEDED if success else EXIT_NOT_SUCCEEDED

    def _event(self, name: str, t_s: float | None = None, **details: Any) -> None:
        """Record an event at ``t_s`` [s] (default: the last tick's time)."""
        when = self.loop.context.now_s if t_s is None else t_s
        self.events.append(_Event(when, name, details))

    def _done(self, name: str) -> bool:
        return any(e.event == name for e in self.events)

    # -- outputs ---------------------------------------------------------------------------

    def _write_outputs(self) -> None:
        args = self.args
        if self.video is not None:
            self.say(f"wrote {args.video} ({self.video.frames} frames at {args.fps} fps)")
        if args.report is not None and self.result is not None:
            args.report.write_text(json.dumps(self._report(), indent=2) + "\n", encoding="utf-8")
            self.say(f"wrote {args.report}")
        if self.recorder is not None and self.result is not None and self.result["status"] != (
                "REJECTED"):
            arrays = self.recorder.arrays()
            if args.log is not None:
                np.savez_compressed(args.log, **arrays)
                self.say(f"wrote {args.log} ({len(arrays['t_s'])} ticks)")
            if args.plot is not None:
                write_plot(args.plot, arrays, title=f"{self.action_name} ({self.goal_text})")
                self.say(f"wrote {args.plot}")

    def _report(self) -> dict[str, Any]:
        phases = []
        for entry in self.feedback:
            if not phases or phases[-1]["phase"] != entry["phase"]:
                phases.append({"phase": entry["phase"], "t_s": entry["t_s"]})
        return {
            "action": self.action_name,
            "goal": dataclasses.asdict(self.goal),
            "start_pose": self.args.start_pose or "standing",
            "plant": dataclasses.asdict(self.args.plant_model),
            "state": {
                "source": self.args.state,
                "estimator": self.args.estimator if self.args.state == "estimate" else None,
                "estimator_params": dict(self.args.estimator_param),
                "sensors": self.args.sensor_model.as_dict(),
                "sensor_seed": self.args.sensor_seed,
                "estimator_config": (None if self.loop.estimator is None
                                     else dataclasses.asdict(self.loop.estimator.config)),
                "command_delay_s": self.args.command_delay,
                "sensor_faults": [dataclasses.asdict(f) for f in self.args.sensor_fault],
            },
            "control_rate_hz": self.args.control_rate,
            "physics_timestep_s": self.args.physics_dt,
            "result": self.result,
            "phases": phases,
            "events": [e.as_dict() for e in self.events],
            "feedback": self.feedback,
            "metrics": None if self.summary is None else self.summary.as_dict(),
            "wall_time_s": round(self.wall_s, 3),
        }


def _metrics_text(summary: Any, *, raised: bool, estimated: bool) -> str:
    s = summary
    parts = []
    if raised:
        parts.append(f"raised foot error RMS {s.raised_foot_rms_mm:.1f} mm "
                     f"(max {s.raised_foot_max_mm:.1f} mm)")
    parts += [f"stance sliding max {s.stance_sliding_max_mm:.2f} mm",
              f"min CoM margin {s.min_com_margin_mm:.0f} mm",
              f"max tilt {s.max_base_tilt_deg:.1f} deg",
              f"QP failures {s.qp_failures}",
              f"tick median {s.tick_median_us:.0f} us (p99 {s.tick_p99_us:.0f} us)",
              f"real-time factor {s.real_time_factor:.2f}"]
    text = "metrics: " + "; ".join(parts)
    if estimated:
        text += (f"\nestimate vs truth: base velocity error RMS "
                 f"{s.estimate_velocity_rms_m_s * 1e3:.1f} mm/s (max "
                 f"{s.estimate_velocity_max_m_s * 1e3:.1f}); height error max "
                 f"{s.estimate_height_max_mm:.2f} mm; roll / pitch error max "
                 f"{s.estimate_roll_max_deg:.2f} / {s.estimate_pitch_max_deg:.2f} deg; drift "
                 f"{s.estimate_horizontal_drift_mm:.1f} mm horizontal, "
                 f"{s.estimate_yaw_drift_deg:.2f} deg yaw")
    return text


# --------------------------------------------------------------------------- entry point


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``go2-wbc``; returns the exit code (see ``go2-wbc --help``)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if hasattr(args, "plant"):  # the commands that simulate
            _check_combinations(args)
        return int(args.run(args))
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except RuntimeError as err:
        # MuJoCo refuses to import under a MUJOCO_GL it does not know: nothing can run.
        if "MUJOCO_GL" not in str(err):
            raise
        print(f"go2-wbc: {err}; unset it, or set one MuJoCo knows (egl, osmesa, glfw)",
              file=sys.stderr)
        return EXIT_UNAVAILABLE


if __name__ == "__main__":
    sys.exit(main())
