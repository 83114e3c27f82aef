"""The options of ``go2-wbc``'s goal commands: the presets (plant, sensors, estimator), the run
and its outputs; every other setting is a ``--set`` (:mod:`sim.cli.settings`).

Their defaults are :class:`sim.episode.Episode`'s (:func:`sim.episode.episode_default`).
"""

from __future__ import annotations

import argparse
from typing import Any, NoReturn

from actions.robot.robot_interface import STATE_SOURCES
from sim.cli.arg_types import float_in, output_file, push
from sim.cli.exit_codes import EXIT_USAGE
from sim.cli.recording_options import add_recording_options
from sim.cli.settings import GOAL_GROUPS, PUSH_AT_S, PUSH_DIR_DEG, add_settings
from sim.episode import episode_default
from sim.plant import PLANT_PRESETS
from sim.sensor_model import SENSOR_PRESETS
from wbc.estimation.estimators import ESTIMATORS

#: Sim time [s] the robot stands before the goal is sent.
SETTLE_S: float = episode_default("settle_s")
__all__ = ["PUSH_AT_S", "PUSH_DIR_DEG", "SETTLE_S", "CliParser", "add_plant_options",
           "add_state_options", "run_options"]


class CliParser(argparse.ArgumentParser):
    """Reports a usage error on one line, naming the option: ``--height: expected ...``."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def add_plant_options(group: Any) -> None:
    """The simulated plant's preset, added to ``group`` (its parameters: ``--set plant.*``)."""
    plant = episode_default("plant")
    group.add_argument("--plant", choices=tuple(PLANT_PRESETS), default=plant,
                       help="the simulated GO2's joints and contacts, which the controller "
                            f"does not know (default: {plant}; 'ideal' matches the "
                            "controller's model; its parameters: --set plant.NAME=VALUE)")


def add_state_options(group: Any) -> None:
    """Where the controller's state comes from: the state source, the estimator and the
    sensors' presets (their parameters: ``--set estimator.*``, ``--set sensors.*``)."""
    group.add_argument("--state", choices=STATE_SOURCES, default=episode_default("state"),
                       help="the controller's state: 'estimate' (default: the state estimator "
                            "on the simulated sensors, as on a real GO2) or 'truth' (the "
                            "simulator's exact state, for comparison)")
    estimator = episode_default("estimator")
    # default None: given with --state truth, it is refused (sim.cli.episode_options)
    group.add_argument("--estimator", choices=tuple(ESTIMATORS), default=None,
                       help="the state estimator: " + "; ".join(
                           f"'{name}': {what}" for name, what in ESTIMATORS.items())
                       + f" (default: {estimator}; its parameters: --set estimator.NAME=VALUE)")
    sensors = episode_default("sensors")
    group.add_argument("--sensors", choices=tuple(SENSOR_PRESETS), default=sensors,
                       help=f"what the simulated GO2 measures (default: {sensors}: its "
                            "IMU, encoders and foot sensors with noise and biases; 'exact': "
                            "no noise; their parameters: --set sensors.NAME=VALUE)")


def run_options() -> argparse.ArgumentParser:
    """Options shared by every goal-sending subcommand."""
    common = CliParser(add_help=False)
    run = common.add_argument_group("simulation")
    add_plant_options(run)
    add_state_options(run)
    add_settings(common, run, GOAL_GROUPS)
    sim_time = float_in(0.0, 3600.0, what="a sim time", unit="s", fmt="g")
    run.add_argument("--realtime", action="store_true",
                     help="pace the simulation to the wall clock (default: as fast as possible)")
    run.add_argument("--viewer", action="store_true",
                     help="open the MuJoCo viewer (implies --realtime); it stays open on "
                          "the final state until you close it (see --set run.viewer_exit); "
                          "without a display ($DISPLAY or $WAYLAND_DISPLAY) it says so and "
                          "runs headless (default: headless)")
    run.add_argument("--cancel-at", type=sim_time, metavar="SECONDS",
                     help="cancel the goal at this simulated time [s]; the robot stands "
                          f"{SETTLE_S:g} s before the goal is sent (default: never)")
    run.add_argument("--push", type=push, metavar="FORCE_N,DURATION_S",
                     help="push the base horizontally with FORCE_N [N] for DURATION_S [s], "
                          f"from {PUSH_AT_S:g} s towards {PUSH_DIR_DEG:g} deg (left; "
                          "--set push.at_s, push.dir_deg change them; default: no push)")
    out = common.add_argument_group("outputs")
    out.add_argument("--metrics", action="store_true",
                     help="measure the run (raised-foot tracking, stance sliding, CoM margin, "
                          "tilt, torques, QP failures, tick times) and print a summary; "
                          "implied by --report (default: off: measuring takes about as long "
                          "as controlling)")
    out.add_argument("--video", type=output_file(".mp4"), metavar="FILE.mp4",
                     help="record an MP4 from a camera tracking the robot, rendered offscreen "
                          "(works without a display or GPU; --set video.fps, video.size, "
                          "video.overlay; default: none)")
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
    add_recording_options(out, listed=False)  # said in the epilog (RECORDING_HELP)
    return common
