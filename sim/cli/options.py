"""The options of ``go2-wbc``'s goal commands: the plant, the state, the run and its outputs.

Their defaults are :class:`sim.episode.Episode`'s (:func:`sim.episode.episode_default`).
"""

from __future__ import annotations

import argparse
from typing import Any, NoReturn

from actions.robot.robot_interface import STATE_SOURCES
from sim.cli.arg_types import (
    estimator_param,
    float_in,
    output_file,
    overlays,
    plant_param,
    push,
    sensor_fault,
    sensor_param,
    video_size,
    whole_in,
)
from sim.cli.exit_codes import EXIT_USAGE
from sim.episode import START_POSES, episode_default
from sim.episode_runner import VIDEO_FPS, VIDEO_SIZE
from sim.plant import PLANT_PRESETS
from sim.scene_overlay import DEFAULT_OVERLAYS
from sim.sensor_faults import FAULT_KINDS
from sim.sensor_model import SENSOR_PRESETS
from wbc.estimation.estimators import ESTIMATORS

#: Sim time [s] the robot stands before the goal is sent.
SETTLE_S: float = episode_default("settle_s")
#: A push's start [s] (during the hold of a high five) and direction [deg] unless given.
PUSH_AT_S, PUSH_DIR_DEG = 3.5, 90.0


class CliParser(argparse.ArgumentParser):
    """Reports a usage error on one line, naming the option: ``--height: expected ...``."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def add_plant_options(group: Any) -> None:
    """The simulated plant and the control and physics rates, added to ``group``."""
    plant = episode_default("plant")
    group.add_argument("--plant", choices=tuple(PLANT_PRESETS), default=plant,
                       help="the simulated GO2's joints and contacts, which the controller "
                            f"does not know (default: {plant}; 'ideal' matches the "
                            "controller's model)")
    _add_params(group, "plant", plant_param, "preset", (
        "joint_damping, joint_friction_loss, joint_armature (every joint), hip_/thigh_/calf_ + "
        "damping/friction_loss/armature (one joint type), foot_friction, torsional_friction, "
        "rolling_friction, condim, cone=elliptic|pyramidal, impratio, foot_radius_m, "
        "payload_kg, payload_offset_m=X,Y,Z"))
    rate = 1.0 / episode_default("control_period_s")
    group.add_argument("--control-rate", type=float_in(10.0, 10000.0, what="a rate",
                                                       unit="Hz", fmt="g"),
                       default=rate, metavar="HZ",
                       help=f"control rate [Hz] (default: {rate:g}; the GO2's usual is 500)")
    group.add_argument("--physics-dt", type=float_in(1e-5, 0.01, what="a timestep",
                                                     unit="s", fmt="g"),
                       default=episode_default("physics_timestep_s"), metavar="SECONDS",
                       help="physics timestep [s]; a whole number of them per control period "
                            "(default: 0.001, or the control period if shorter)")


def add_state_options(group: Any) -> None:
    """Where the controller's state comes from, the sensors, a command delay and faults."""
    group.add_argument("--state", choices=STATE_SOURCES, default=episode_default("state"),
                       help="the controller's state: 'estimate' (default: the state estimator "
                            "on the simulated sensors, as on a real GO2) or 'truth' (the "
                            "simulator's exact state, for comparison)")
    estimator = episode_default("estimator")
    group.add_argument("--estimator", choices=tuple(ESTIMATORS), default=estimator,
                       help="the state estimator: " + "; ".join(
                           f"'{name}': {what}" for name, what in ESTIMATORS.items())
                       + f" (default: {estimator}; see the README's State estimation)")
    _add_params(group, "estimator", estimator_param, "estimator", (
        "use_foot_force=false (contact from the schedule alone: a robot without foot sensors), "
        "trust_timeout_s, foot_force_offset and foot_force_gain (the foot sensors' counts = "
        "offset + gain x N: one number or four, FL,FR,RL,RR), foot_force_on_n, "
        "foot_force_off_n, ..."))
    group.add_argument("--calibrate", type=float_in(0.2, 60.0, what="a duration", unit="s",
                                                    fmt="g"),
                       default=episode_default("calibrate_s") or None, metavar="SECONDS",
                       help="before the goal, stand SECONDS (2 is enough) with the centre of "
                            "mass circling 4.5 cm: learn each foot sensor's offset and gain "
                            "and check the IMU at rest (default: no calibration)")
    sensors = episode_default("sensors")
    group.add_argument("--sensors", choices=tuple(SENSOR_PRESETS), default=sensors,
                       help=f"what the simulated GO2 measures (default: {sensors}: its "
                            "IMU, encoders and foot sensors with noise and biases; 'exact': "
                            "no noise)")
    _add_params(group, "sensor", sensor_param, "preset", (
        "gyro_noise_rad_s, gyro_bias_rad_s, accel_noise_m_s2, accel_bias_m_s2, "
        "attitude_time_constant_s, joint_position_noise_rad, joint_velocity_noise_rad_s, "
        "foot_force_gain, ..."))
    seed = episode_default("sensor_seed")
    group.add_argument("--sensor-seed", type=whole_in(0, 2**31 - 1, what="a seed"), default=seed,
                       metavar="N", help=f"seed of the sensors' noise and biases (default: {seed})")
    group.add_argument("--sensor-fault", type=sensor_fault, action="append", default=[],
                       metavar="KIND,AT_S,DURATION_S[,NAME]",
                       help="a sensor fault from sim time AT_S for DURATION_S, repeatable; "
                            f"KIND: {', '.join(FAULT_KINDS)}; NAME: the foot of a foot fault "
                            "(default FR) or the joint of joint_nan (default FR_thigh_joint)")
    delay = episode_default("command_delay_s")
    group.add_argument("--command-delay", type=float_in(0.0, 0.1, what="a delay", unit="s",
                                                        fmt="g"),
                       default=delay, metavar="SECONDS",
                       help="time [s] between a command and the motor drivers applying it, a "
                            f"whole number of control periods (default: {delay:g}; "
                            "legged_control simulates a Unitree robot with 0.009)")


def _add_params(group: Any, what: str, parse: Any, defaults_from: str, names: str) -> None:
    """``--WHAT-param NAME=VALUE``, repeatable: one parameter changed by name."""
    group.add_argument(f"--{what}-param", type=parse, action="append", default=[],
                       metavar="NAME=VALUE",
                       help=f"change one {what} parameter, repeatable: {names} (default: the "
                            f"{defaults_from}'s values)")


def run_options() -> argparse.ArgumentParser:
    """Options shared by every goal-sending subcommand."""
    common = CliParser(add_help=False)
    run = common.add_argument_group("simulation")
    add_plant_options(run)
    add_state_options(run)
    sim_time = float_in(0.0, 3600.0, what="a sim time", unit="s", fmt="g")
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
    run.add_argument("--start-pose", choices=START_POSES, default=None,
                     help="pose the robot starts in (default: lying for 'stand', "
                          "standing otherwise)")
    run.add_argument("--cancel-at", type=sim_time, metavar="SECONDS",
                     help="cancel the goal at this simulated time [s]; the robot stands "
                          f"{SETTLE_S:g} s before the goal is sent (default: never)")
    run.add_argument("--push", type=push, metavar="FORCE_N,DURATION_S",
                     help="push the base horizontally with FORCE_N [N] for DURATION_S [s] "
                          "(default: no push)")
    run.add_argument("--push-at", type=sim_time, metavar="SECONDS",
                     help=f"simulated time [s] the push starts (default: {PUSH_AT_S:g}, during the "
                          f"hold of a high five; goals are sent at {SETTLE_S:g} s)")
    run.add_argument("--push-dir", type=float_in(-360.0, 360.0, what="an angle", unit="deg",
                                                 fmt="g"),
                     metavar="DEGREES",
                     help="push direction [deg] relative to the robot's heading: 0 forward, "
                          f"90 left, 180 backward, 270 right (default: {PUSH_DIR_DEG:g})")
    out = common.add_argument_group("outputs")
    out.add_argument("--metrics", action="store_true",
                     help="measure the run (raised-foot tracking, stance sliding, CoM margin, "
                          "tilt, torques, QP failures, tick times) and print a summary; "
                          "implied by --report (default: off: measuring takes about as long "
                          "as controlling)")
    out.add_argument("--video", type=output_file(".mp4"), metavar="FILE.mp4",
                     help="record an MP4 from a camera tracking the robot, rendered offscreen "
                          "(works without a display or GPU; default: none)")
    out.add_argument("--fps", type=whole_in(1, 240, what="frames per second"), default=None,
                     metavar="N",
                     help=f"video frame rate [1/s] of simulated time (default: {VIDEO_FPS})")
    width, height = VIDEO_SIZE
    out.add_argument("--video-size", type=video_size, default=None, metavar="WxH",
                     help=f"video frame size in pixels (default: {width}x{height})")
    out.add_argument("--overlay", type=overlays, default=None, metavar="LIST",
                     help="what the viewer and the video draw over the robot, comma-separated: "
                          "com (the centre of mass and its ground projection), polygon (the "
                          "support polygon of the loaded feet, its margin inside), forces (the "
                          "commanded contact forces), measured (MuJoCo's contact forces), "
                          "target (the raised foot's target and its trace); or all, or none "
                          f"(default: {','.join(DEFAULT_OVERLAYS)})")
    out.add_argument("--plot", type=output_file(".png", ".pdf", ".svg"), metavar="FILE.png",
                     help="plot raised-foot height vs target, CoM margin to the support edge, "
                          "FR normal force, the state estimate's height and velocity errors "
                          "and control tick time against sim time "
                          "(default: none)")
    out.add_argument("--report", type=output_file(".json"), metavar="FILE.json",
                     help="write the result, the feedback with sim times and the run metrics "
                          "(default: none)")
    out.add_argument("--log", type=output_file(".npz"), metavar="FILE.npz",
                     help="write per-tick arrays: t_s, q, v (the controller's state, "
                          "Pinocchio convention, joint_names beside), q_true, v_true (the "
                          "simulator's exact state), estimate_contact, estimate_flags, tau, "
                          "raised-foot target and position, phase, "
                          "MuJoCo foot contact forces (4x3), CoM margin, QP status, tick time "
                          "(default: none)")
    return common
