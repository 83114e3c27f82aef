"""``go2-wbc bridge``: the simulated GO2 on the robot's DDS topics until Ctrl-C, SIGTERM or
``--duration`` (:class:`sim.dds_bridge.DdsBridge`)."""

from __future__ import annotations

import argparse
import gc
import json
import signal
import sys
import time
from typing import Any

from actions.robot.realtime_priority import BRIDGE_PRIORITY, RealtimeScheduling
from sim.bridge_config import (
    BRIDGE_POSES,
    DEFAULT_RATE_HZ,
    PHYSICS_TIMESTEP_S,
    BridgeConfig,
    steps_per_state,
)
from sim.cli.arg_types import float_in, output_file, whole_in
from sim.cli.dds_options import add_dds_options, add_priority_option
from sim.cli.exit_codes import EXIT_NOT_SUCCEEDED, EXIT_SUCCEEDED, EXIT_UNAVAILABLE, EXIT_USAGE
from sim.cli.settings import add_settings
from sim.command_slot import DAMPING_KD, DEFAULT_COMMAND_TIMEOUT_S, STAND_KD, STAND_KP
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS, Plant
from sim.sensor_model import DEFAULT_SENSORS, SENSOR_PRESETS, SensorModel
from sim.state_framing import FRAMINGS, GO2, UNITREE_PYTHON, UNITREE_PYTHON_RATE_HZ
from wbc.core.errors import ConfigurationError, WbcError
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC

EXAMPLES_HELP = f"""\
A controller written for a real GO2 runs against it unchanged: it reads
{LOW_STATE_TOPIC} (LowState_, from the simulated sensors) and writes {LOW_CMD_TOPIC}
(LowCmd_, checked as the robot checks it: head FE EF, level_flag 0xFF, CRC).
Before its first valid command the robot stands on the bridge's own joint PD
(kp {STAND_KP:g}, kd {STAND_KD:g}); when commands stop for --command-timeout the motors go
to damping (kp 0, kd {DAMPING_KD:g}, tau 0) and it sits down; the next valid command
drives them again. The exact state goes out on {SIM_TRUTH_TOPIC}, for evaluation
(a controller never reads it). For latency statistics a controller echoes the
tick of the LowState_ it answers in LowCmd_.reserve.

--framing unitree-cpp or unitree-python frames the states and applies the
commands as Unitree's C++ or Python simulator (unitree_mujoco) does, to validate a
controller against them: head 00 00, foot_force 0, no stand PD (the robot starts
lying, no torque until the first command), the last command held (no damping);
unitree-python also sends crc 0 and tick 0 at 200 Hz with 10-50 ms gaps and turns
each command into one torque held until the next. The domain does not tell them
apart: unitree_mujoco's configs use domain 1 on lo too, the default here.

examples:
  go2-wbc bridge                              # domain 1 on lo at 500 Hz, until Ctrl-C
  go2-wbc bridge --rate 1000 --viewer
  go2-wbc bridge --duration 60 --report bridge.json --log truth.npz
  go2-wbc bridge --plant identified --sensors exact --pose lying
  go2-wbc bridge --framing unitree-python     # as Unitree's Python simulator

"""
EXIT_HELP = f"""\
exit status:
  {EXIT_SUCCEEDED:>3}  stopped by Ctrl-C, SIGTERM or --duration; the summary is printed
  {EXIT_NOT_SUCCEEDED:>3}  the simulation diverged (the summary is printed)
  {EXIT_USAGE:>3}  bad arguments (the message names the argument and what is valid)
  {EXIT_UNAVAILABLE:>3}  the DDS domain cannot be joined here
"""
#: The option that sets each :class:`BridgeConfig` field.
_OPTIONS = {"domain_id": "--domain", "interface": "--interface", "rate_hz": "--rate",
            "plant": "--set plant", "sensors": "--set sensors",
            "sensor_seed": "--sensor-seed", "command_delay_s": "--command-delay",
            "command_timeout_s": "--command-timeout", "pose": "--pose",
            "framing": "--framing"}


def _rate(text: str) -> float:
    rate = float_in(1.0, 1.0 / PHYSICS_TIMESTEP_S, what="a rate", unit="Hz", fmt="g")(text)
    try:
        steps_per_state(rate)
    except ConfigurationError as err:
        raise argparse.ArgumentTypeError(str(err).removeprefix("rate_hz: ")) from None
    return rate


def add_bridge_command(sub: Any) -> argparse.ArgumentParser:
    """Add ``bridge`` to the ``go2-wbc`` subcommands ``sub``."""
    text = "serve the simulated GO2 on the robot's DDS topics, as unitree_mujoco does"
    bridge = sub.add_parser("bridge", help=text, description=text[0].upper() + text[1:] + ".",
                            epilog=EXAMPLES_HELP + EXIT_HELP,
                            formatter_class=argparse.RawDescriptionHelpFormatter)
    # main() checks the plant of every command that has --plant as an episode
    # (sim.cli.episode_options.check_options), which reads the control rate and the physics
    # timestep: the plant is checked at the GO2's usual 500 Hz control rate, 1 kHz physics.
    bridge.set_defaults(run=run_bridge, parser=bridge, physics_dt=PHYSICS_TIMESTEP_S,
                        control_rate=DEFAULT_RATE_HZ)
    dds = bridge.add_argument_group("DDS")
    add_dds_options(dds, flag_help=None)  # --domain, --interface: as the commands that use it
    add_priority_option(dds, default=BRIDGE_PRIORITY, loop="the physics loop")
    dds.add_argument("--rate", dest="state_rate", type=_rate, metavar="HZ",
                     help=f"LowState_ rate [Hz]: 1000 divided by a whole number (default: "
                          f"{DEFAULT_RATE_HZ:g}, the GO2's usual; {UNITREE_PYTHON_RATE_HZ:g} "
                          "with --framing unitree-python, as its SIMULATE_DT); commands are "
                          "taken at every 1 ms physics step")
    dds.add_argument("--framing", choices=tuple(FRAMINGS), default=GO2,
                     help="frame states and apply commands as a GO2 does, or as Unitree's C++ "
                          "or Python simulator does (see below; default: go2)")
    sim = bridge.add_argument_group("simulation")
    sim.add_argument("--plant", choices=tuple(PLANT_PRESETS), default=DEFAULT_PLANT,
                     help=f"the simulated GO2's joints and contacts (default: {DEFAULT_PLANT})")
    sim.add_argument("--sensors", choices=tuple(SENSOR_PRESETS), default=DEFAULT_SENSORS,
                     help=f"what the simulated GO2 measures (default: {DEFAULT_SENSORS}: noise "
                          "and biases; 'exact': none)")
    add_settings(bridge, sim, ("plant", "sensors"))
    sim.add_argument("--sensor-seed", type=whole_in(0, 2**31 - 1, what="a seed"), default=0,
                     metavar="N", help="seed of the sensors' noise and biases (default: 0)")
    sim.add_argument("--command-delay", type=float_in(0.0, 0.1, what="a delay", unit="s",
                                                      fmt="g"),
                     default=0.0, metavar="S",
                     help="time [s] between taking a command and the drivers applying it, "
                          "whole 1 ms physics steps (default: 0)")
    sim.add_argument("--command-timeout", type=float_in(0.001, 10.0, what="a timeout",
                                                        unit="s", fmt="g"),
                     default=DEFAULT_COMMAND_TIMEOUT_S, metavar="S",
                     help="time [s] without a valid command before the motors go to damping "
                          f"(default: {DEFAULT_COMMAND_TIMEOUT_S:g}: 50 missed commands at "
                          "500 Hz)")
    sim.add_argument("--pose", choices=BRIDGE_POSES,
                     help="the pose the robot starts and stands in (default: standing; "
                          "lying with a Unitree framing, which has no stand PD)")
    sim.add_argument("--duration", type=float_in(0.001, 7 * 86400.0, what="a duration",
                                                 unit="s", fmt="g"),
                     metavar="S", help="stop after S seconds (default: run until Ctrl-C or "
                                       "SIGTERM)")
    sim.add_argument("--viewer", action="store_true",
                     help="open the MuJoCo viewer; closing it leaves the bridge running "
                          "(default: headless)")
    out = bridge.add_argument_group("outputs")
    out.add_argument("--report", type=output_file(".json"), metavar="FILE.json",
                     help="write the configuration and the statistics at exit (default: "
                          "none)")
    out.add_argument("--log", type=output_file(".npz"), metavar="FILE.npz",
                     help=f"write the truth of every published state at exit ({SIM_TRUTH_TOPIC}'s "
                          "arrays: tick, t_s, q, v, foot_position_m, foot_force_n; joint_names, "
                          "leg_names; default: none)")
    return bridge


def bridge_config(args: argparse.Namespace) -> BridgeConfig:
    """The parsed options as a :class:`BridgeConfig`; a bad one is a usage error (exit 2)."""
    unitree = args.framing != GO2
    rate = args.state_rate or (UNITREE_PYTHON_RATE_HZ if args.framing == UNITREE_PYTHON
                                 else DEFAULT_RATE_HZ)
    try:
        return BridgeConfig(
            domain_id=args.domain, interface=args.interface, rate_hz=rate,
            plant=Plant.preset(args.plant).with_params(**dict(args.plant_param)),
            sensors=SensorModel.preset(args.sensors).with_params(**dict(args.sensor_param)),
            sensor_seed=args.sensor_seed, command_delay_s=args.command_delay,
            command_timeout_s=args.command_timeout,
            pose=args.pose or ("lying" if unitree else "standing"), viewer=args.viewer,
            log_truth=args.log is not None, framing=args.framing)
    except ConfigurationError as err:
        field, _, detail = str(err).partition(": ")
        option = _OPTIONS.get(field)
        parser: argparse.ArgumentParser = args.parser
        name, sep, rest = detail.partition(": ")
        if option and option.startswith("--set ") and sep and " " not in name:
            option, detail = f"{option}.{name}", rest  # the setting's path, as it was given
        parser.error(f"{option}: {detail}" if option else str(err))


def run_bridge(args: argparse.Namespace) -> int:
    """Run ``go2-wbc bridge``; returns the exit code."""
    from sim.dds_bridge import DdsBridge

    config = bridge_config(args)

    def say(text: str) -> None:
        print(text, flush=True)

    bridge = DdsBridge(config, on_event=lambda t_s, text: say(f"[{t_s:8.3f} s] {text}"))
    stopped_by = ["--duration" if args.duration is not None else "the end"]
    previous: dict[int, Any] = {}
    try:
        try:
            bridge.start()
        except Exception as err:  # noqa: BLE001 - Cyclone's failures vary in type
            print(f"go2-wbc bridge: cannot join DDS domain {config.domain_id} on "
                  f"{config.interface!r}: {' '.join(str(err).split())}", file=sys.stderr)
            return EXIT_UNAVAILABLE
        for line in _header(config, args.duration):
            say(line)

        def on_signal(signum: int, _frame: Any) -> None:
            stopped_by[0] = signal.Signals(signum).name
            bridge.stop()

        for stopping in (signal.SIGINT, signal.SIGTERM):
            previous[stopping] = signal.signal(stopping, on_signal)
        cpu_s = time.process_time()
        code = EXIT_SUCCEEDED
        # What start-up allocated stays out of the collector's scans: a full collection of
        # it would stall the loop for ~20 ms (sim.episode_loop.startup_objects_frozen).
        gc.freeze()
        try:
            with RealtimeScheduling(args.rt_priority) as scheduling:
                say(scheduling.describe())
                bridge.run(args.duration)
        except WbcError as err:
            say(f"[{bridge.sim.time_s:8.3f} s] the simulation stopped: {err}")
            stopped_by[0], code = "an error", EXIT_NOT_SUCCEEDED
        finally:
            gc.unfreeze()
        cpu_s = time.process_time() - cpu_s
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        bridge.close()
    cpu_percent = 100.0 * cpu_s / bridge.wall_s if bridge.wall_s > 0.0 else 0.0
    say(f"stopped by {stopped_by[0]} after {bridge.wall_s:.3f} s (sim {bridge.sim.time_s:.3f} s, "
        f"{bridge.steps} physics steps); CPU {cpu_percent:.0f} % of one core")
    for line in bridge.stats.summary_lines():
        say(line)
    if bridge.gaps is not None:
        gaps = bridge.gaps.report()
        say(f"gaps as Unitree's Python simulator has them: {gaps['gaps']} "
            f"({gaps['states_withheld']} states not sent, {gaps['states_repeated']} sent again "
            "with the physics halted)")
    if args.report is not None:
        report = bridge.report() | {"stopped_by": stopped_by[0],
                                    "cpu_percent": round(cpu_percent, 1)}
        args.report.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
        say(f"wrote {args.report}")
    if args.log is not None and bridge.truth_log is not None:
        count = bridge.truth_log.save(args.log)
        say(f"wrote {args.log} ({count} states)")
    return code


def _header(config: BridgeConfig, duration_s: float | None) -> list[str]:
    """What the bridge says when it starts."""
    until = "Ctrl-C or SIGTERM" if duration_s is None else f"{duration_s:g} s have passed"
    delay = (f"; commands applied {config.command_delay_s * 1e3:g} ms after they are taken"
             if config.delay_steps else "")
    if config.framing == GO2:
        drivers = (f"{config.pose} on the bridge's joint PD (kp {STAND_KP:g}, kd {STAND_KD:g}) "
                   f"until the first valid command; damping (kd {DAMPING_KD:g}) after "
                   f"{config.command_timeout_s:g} s without one")
    else:
        drivers = (f"{config.pose}, no torque until the first valid command; the last one "
                   "held (no damping)")
    return [
        (f"bridge: DDS domain {config.domain_id} on {config.interface}: {LOW_STATE_TOPIC} at "
         f"{config.rate_hz:g} Hz and {SIM_TRUTH_TOPIC} out, {LOW_CMD_TOPIC} in"),
        f"framing {config.framing}: {FRAMINGS[config.framing]}",
        f"{config.plant_model.describe()}; physics {config.physics_timestep_s * 1e3:g} ms"
        + delay,
        f"{config.sensor_model.describe()}, seed {config.sensor_seed}",
        drivers,
        f"running until {until}",
    ]
