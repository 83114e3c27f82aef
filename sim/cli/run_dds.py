"""``go2-wbc run --dds``: the whole-body controller of a GO2 (or of the simulator bridge) on DDS.

It waits for the robot's first ``rt/lowstate``, builds the state estimator, the controller,
the control loop and the DDS action servers, stands the robot up if it is down, and runs on the
wall clock (:class:`~actions.robot.realtime_loop.RealtimeLoop`) until Ctrl-C, SIGTERM or
``--duration``: then it cancels the running goal, sits the robot down and damps the motors
before it exits (a second Ctrl-C damps at once). It prints a status line a second and a
summary; ``--report`` and ``--log`` keep the figures and the per-tick arrays. ``--dry-run``
reads the robot and prints what it would send, publishing nothing.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import IO, Any

from actions.robot.realtime_priority import CONTROLLER_PRIORITY, RealtimeScheduling
from sim.cli.arg_types import float_in, output_file
from sim.cli.dds_options import add_dds_options, add_priority_option
from sim.cli.exit_codes import (
    EXIT_CODES_HELP,
    EXIT_INTERRUPTED,
    EXIT_SUCCEEDED,
    EXIT_UNAVAILABLE,
    EXIT_USAGE,
)
from sim.cli.recording_options import (
    add_recording_options,
    open_recording_process,
    recording_summary,
)
from sim.cli.ros2_command import start_ros2_node
from sim.cli.settings import add_settings
from wbc.core.errors import ConfigurationError
from wbc.estimation.estimators import DEFAULT_ESTIMATOR, ESTIMATORS
from wbc.robot_io.unitree_sdk import SDK_LEG_MOTORS

#: Control rates [Hz] the command runs at (the GO2's usual low-level rate first).
RATES_HZ = (500, 1000)
#: Default longest wait [s] for the robot's first state.
WAIT_S = 5.0
#: Why ``run`` refuses ``--set estimator.trust_timeout_s``.
_STALE_SET_BY = "set by --stale-after (one limit for the watchdog and the estimator)"

RUN_HELP = """\
examples:
  go2-wbc bridge &                          # the simulated GO2 on DDS (domain 1, lo)
  go2-wbc run --dds                         # its controller; Ctrl-C brings it to rest
  go2-wbc high-five --dds                   # a goal to it, from another terminal
  go2-wbc run --dds --dry-run --duration 5  # read the robot, print what would be sent
  go2-wbc run --dds --domain 0 --interface eth0 --report run.json --log run.npz

a real GO2 needs domain 0 on the interface of its Ethernet link, sport mode released first
(Unitree's MotionSwitcher), a hoist for the first tests, and a --dry-run before anything.

the stream: the first states say which kind of robot sends them (printed at start): a GO2
or go2-wbc bridge (head FE EF, CRC checked, new samples by their tick), Unitree's C++
simulator (head 00 00, CRC checked) or Unitree's Python simulator (head 00 00, crc 0 and
tick 0: new samples by their content). A frame of another kind, or with a wrong CRC, is
dropped and counted; a stream that keeps arriving but never changes is named in the fault.

staleness: one limit, for the loop's watchdog and the estimator's trust limit alike: without
a new state for that long the controller's safe command is sent and the running goal ends
ABORTED. By default it is 20 periods of the state rate measured at start, or twice the
longest gap seen then, within [20, 250] ms: 40 ms at 500 Hz, 100 ms at 200 Hz, where
Unitree's Python simulator has gaps of 10 to 50 ms. --stale-after S sets it.

"""


def add_run_command(sub: Any) -> None:
    """Add ``run`` to the ``go2-wbc`` subcommands."""
    run = sub.add_parser(
        "run", help="run the whole-body controller of a robot on DDS (go2-wbc run --dds)",
        description="Run the whole-body controller and the action servers of a GO2 (or of\n"
                    "'go2-wbc bridge') over DDS, on the wall clock, until Ctrl-C.",
        epilog=RUN_HELP + EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    dds = run.add_argument_group("robot")
    add_dds_options(dds, flag_help="control a robot over DDS (required, no default: the "
                                   "simulated robot runs with the goal commands, or as "
                                   "'go2-wbc bridge')")
    add_priority_option(dds, default=CONTROLLER_PRIORITY, loop="the control loop")
    dds.add_argument("--control-rate", type=int, choices=RATES_HZ, default=RATES_HZ[0],
                     metavar="HZ", help=f"control rate [Hz]: {' or '.join(map(str, RATES_HZ))} "
                                        f"(default: {RATES_HZ[0]}, the GO2's usual)")
    dds.add_argument("--dry-run", action="store_true",
                     help="read the robot and print what would be sent; publish no command "
                          "(default: publish)")
    dds.add_argument("--wait", type=float_in(0.1, 600.0, what="a wait", unit="s", fmt="g"),
                     default=WAIT_S, metavar="S",
                     help=f"longest wait for the robot's first state [s] (default: {WAIT_S:g})")
    dds.add_argument("--duration", type=float_in(0.01, 1e6, what="a duration", unit="s",
                                                 fmt="g"),
                     metavar="S", help="come to rest and exit after this many seconds "
                                       "(default: run until Ctrl-C)")
    dds.add_argument("--remote", action="store_true",
                     help="walk on the GO2's own remote (LowState_.wireless_remote): left "
                          "stick forward and sideways, right stick turning (default: "
                          "ignored; rt/cmd_vel is read either way)")
    dds.add_argument("--no-stand", action="store_true",
                     help="do not stand a robot that is down at the start (default: stand it)")
    dds.add_argument("--no-align", action="store_true",
                     help="tick on the loop's own deadlines only (default: move them to the "
                          "robot's state arrivals, waiting up to half a period a tick: the command "
                          "then answers each state within about the tick's own time)")
    dds.add_argument("--stale-after", type=float_in(0.001, 1.0, what="a time", unit="s",
                                                    fmt="g"),
                     metavar="S", help="send the safe command after this long without a new "
                                       "state [s], the watchdog's and the estimator's limit "
                                       "(default: from the rate measured at start, see below)")
    dds.add_argument("--calibrate", type=float_in(0.2, 60.0, what="a duration", unit="s",
                                                  fmt="g"),
                     metavar="S", help="once the robot stands, learn each foot sensor's "
                                       "offset and gain and check the IMU at rest: S seconds "
                                       "of the centre of mass circling 4.5 cm, goals refused "
                                       "meanwhile (2 is enough; default: no calibration, the "
                                       "given or default one)")
    dds.add_argument("--estimator", choices=tuple(ESTIMATORS), default=DEFAULT_ESTIMATOR,
                     help=f"the state estimator (default: {DEFAULT_ESTIMATOR})")
    add_settings(run, dds, ("estimator", "controller"), refused={
        "estimator.trust_timeout_s": _STALE_SET_BY,
        "controller.solver.control_period_s": "set by --control-rate"})
    out = run.add_argument_group("outputs")
    out.add_argument("--report", type=output_file(".json"), metavar="FILE.json",
                     help="write the run's figures: rate, deadline misses, per-stage tick "
                          "times, the robot's counters, the goals' ends (default: none)")
    out.add_argument("--log", type=output_file(".npz"), metavar="FILE.npz",
                     help="write per-tick arrays (actions.robot.tick_log: the state tick "
                          "answered, the estimate, status, foot targets, stage times; "
                          "default: none)")
    add_recording_options(out)
    run.set_defaults(run=run_dds, parser=run)


def run_dds(args: argparse.Namespace, *, stream: IO[str] | None = None) -> int:
    """``go2-wbc run --dds``; returns the exit status."""
    if not args.dds:
        args.parser.error("--dds: required ('run' drives a robot over DDS; the simulated "
                          "robot: go2-wbc high-five, stand, ..., or go2-wbc bridge)")
    from actions.dds.dds_action_bridge import DdsActionBridge
    from actions.robot.control_loop import ControlLoop
    from actions.robot.dds_robot import DdsRobot, NoRobotStateError
    from actions.robot.foot_calibration import CalibrateWhenStanding
    from actions.robot.realtime_loop import RealtimeLoop, stop_on_signals
    from actions.robot.rest_sequence import RestSettings
    from actions.robot.tick_log import TickLog
    from actions.robot.velocity_inputs import VelocityInputs
    from sim.episode_loop import startup_objects_frozen
    from wbc.controller.controller_config import ControllerConfig
    from wbc.controller.whole_body_controller import WholeBodyController
    from wbc.estimation.estimators import make_estimator

    out = stream or sys.stdout
    recording: Any = None  # --mcap, --foxglove: every line said is among its channels

    def say(text: str) -> None:
        out.write(text + "\n")
        out.flush()
        if recording is not None:
            recording.line(text, loop.robot.time_s)

    period_s = 1.0 / args.control_rate
    params = dict(args.estimator_param)  # --set refused trust_timeout_s: _STALE_SET_BY
    try:
        config = ControllerConfig(solver={"control_period_s": period_s}).with_values(
            dict(args.controller_param))
    except ConfigurationError as err:
        args.parser.error(f"--set controller.{err}")
    robot = bridge = ros_node = inputs = None
    try:
        try:
            make_estimator(args.estimator, control_period_s=period_s, **params)
        except ConfigurationError as err:
            name, sep, detail = str(err).partition(": ")
            args.parser.error(f"--set estimator.{name}: {detail}" if sep and " " not in name
                              else f"--set estimator: {err}")
        robot = DdsRobot(domain_id=args.domain, interface=args.interface, dry_run=args.dry_run)
        say(f"waiting for rt/lowstate on DDS domain {args.domain} (interface "
            f"{args.interface})...")
        try:
            robot.wait_for_first_state(args.wait)
        except NoRobotStateError as err:
            print(f"go2-wbc: {err}", file=sys.stderr)
            return EXIT_UNAVAILABLE
        say(robot.stream.describe())
        stale_after_s = args.stale_after or robot.stale_after_s
        say(f"staleness limit {stale_after_s * 1e3:.0f} ms (watchdog and estimator) "
            + ("from --stale-after" if args.stale_after else
               "from the rate measured at start (--stale-after to change it)"))
        if robot.stream.foot_force_absent and "use_foot_force" not in params:
            params["use_foot_force"] = False
            say("foot_force is 0 in every state (as Unitree's simulators send): foot contact "
                "from the schedule only (estimator use_foot_force=false)")
        estimator = make_estimator(args.estimator, control_period_s=period_s,
                                   trust_timeout_s=stale_after_s, **params)
        say("feet: " + estimator.foot_calibration.describe()
            + ("" if estimator.config.use_foot_force else " (unused: use_foot_force=false)"))
        loop = ControlLoop(robot, WholeBodyController(config),
                           estimator=estimator)
        bridge = DdsActionBridge(loop, domain_id=args.domain, interface=args.interface)
        ros_node = start_ros2_node(args, loop, say)  # --ros2: the same actions on ROS 2
        rt = RealtimeLoop(loop, rate_hz=args.control_rate, bridge=bridge,
                          stale_after_s=stale_after_s,
                          align_s=0.0 if args.no_align else None,
                          rest=RestSettings(stand_on_start=not args.no_stand))
        inputs = VelocityInputs(loop, domain_id=args.domain, interface=args.interface,
                                remote=(lambda: robot.wireless_remote) if args.remote else None,
                                say=say)
        rt.callbacks.append(inputs)
        log = TickLog() if args.log is not None else None
        if log is not None:
            rt.callbacks.append(log.record)
        rt.callbacks.append(_StatusPrinter(say, dry_run=args.dry_run))
        recording = open_recording_process(args, control_period_s=period_s, metadata={
            "command": "run --dds", "control_rate_hz": str(args.control_rate),
            "estimator": args.estimator, "dry_run": str(args.dry_run)})
        if recording is not None:
            from actions.robot.realtime_recording import RealtimeRecording
            from sim.gait_view import walking_motion

            rt.callbacks.append(RealtimeRecording(recording, walking_of=walking_motion))
            if recording.port is not None:
                say(f"foxglove: serving ws://127.0.0.1:{recording.port}")
        calibration = None
        if args.calibrate is not None:
            calibration = CalibrateWhenStanding(args.calibrate, say)
            rt.callbacks.append(calibration)
        say(f"controlling at {args.control_rate} Hz; actions served: "
            f"{', '.join(bridge.action_names)}; velocity commands from rt/cmd_vel"
            + (" and the remote" if args.remote else "")
            + (" (DRY RUN: no command is published)" if args.dry_run else "")
            + "; Ctrl-C to bring the robot to rest and exit")
        rt.start()
        if not loop.ready:
            say(f"not controlling yet: {loop.fallback.log.reason}; motors damping")
        if rt.rest.stand is not None:
            say(f"the robot is down (base at {loop.context.q[2]:.3f} m): standing it up"
                + (" (dry run: printed, not sent)" if args.dry_run else ""))
        with (startup_objects_frozen(), stop_on_signals(rt),
              RealtimeScheduling(args.rt_priority) as scheduling):
            say(scheduling.describe())
            rt.run(duration_s=args.duration)
        report = rt.report()
        report["velocity_inputs"] = inputs.report()
        if calibration is not None:
            report["calibration"] = (
                calibration.report.as_dict() if calibration.report is not None
                else {"abandoned": calibration.abandoned or "the robot never stood still"})
        say(_summary(report))
        if args.report is not None:
            args.report.write_text(json.dumps(report, indent=2, default=str) + "\n")
            say(f"report: {args.report}")
        if log is not None:
            log.save(args.log, rt)
            say(f"log: {args.log} ({len(log)} ticks)")
        if recording is not None:
            recording.close()
            out.write(recording_summary(args, recording) + "\n")
            recording = None
        return EXIT_INTERRUPTED if rt.rest.stop_reason.startswith("SIG") else EXIT_SUCCEEDED
    except ConfigurationError as err:
        print(f"go2-wbc: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    finally:
        if recording is not None:  # an error mid-run: the file still gets its summary
            recording.close()
        if ros_node is not None:
            ros_node.close()
        if inputs is not None:
            inputs.close()
        if bridge is not None:
            bridge.close()
        if robot is not None:
            robot.close()


class _StatusPrinter:
    """A status line a second (and, in a dry run, the command that would be sent)."""

    def __init__(self, say: Any, *, dry_run: bool) -> None:
        self.say = say
        self.dry_run = dry_run
        self._next_s = 1.0

    def __call__(self, rt: Any) -> None:
        now = rt.loop.robot.time_s
        if now < self._next_s:
            return
        self._next_s = now + 1.0
        self.say(rt.status_line())
        robot = rt.loop.robot.robot
        if self.dry_run and robot.last_command is not None:
            cmd = robot.last_command
            rows = ", ".join(
                ("q stop" if cmd.kp[k] == 0.0 else f"q {cmd.q[k]:+.3f}")
                + f" kp {cmd.kp[k]:g} kd {cmd.kd[k]:g} tau {cmd.tau[k]:+.2f}"
                for k in range(0, SDK_LEG_MOTORS, 3))
            self.say(f"  would send (SDK slots 0, 3, 6, 9: FR, FL, RR, RL hips; reserve "
                     f"{robot.answer_tick}): {rows}")


def _summary(report: dict[str, Any]) -> str:
    series = report["series"]
    stages = ", ".join(f"{name} {series[name]['mean_ms']:.3f}/{series[name]['p99_ms']:.3f}"
                       for name in ("read", "actions", "controller", "write", "bridge",
                                    "hooks", "gc"))
    robot = report["robot"]
    modes = "".join(f"\n  {mode['t_s']:.2f} s: {mode['mode']}"
                    + (f" ({mode['reason']})" if mode["reason"] else "")
                    for mode in report.get("modes", [])[1:])
    return (f"stopped ({report['stop']['reason'] or 'done'}; "
            f"{'; '.join(report['stop']['notes']) or 'no goal to unwind'}) after "
            f"{report['duration_s']:.1f} s: {report['ticks']} ticks at {report['rate_hz']:g} Hz, "
            f"{report['deadline_misses']} deadline misses, {report['no_fresh_state_ticks']} "
            f"ticks without a fresh state, {report['watchdog_trips']} watchdog trips; "
            f"robot: {robot.get('ticks_skipped', 0)} state ticks skipped, "
            f"{robot.get('bad_frames', 0)} bad frames, {robot.get('commands_sent', 0)} "
            f"commands\n  tick [ms] mean/p99: {stages}; whole tick "
            f"{series['tick']['mean_ms']:.3f}/{series['tick']['p99_ms']:.3f}, cpu "
            f"{series['cpu']['mean_ms']:.3f}/{series['cpu']['p99_ms']:.3f}, latency "
            f"{series['latency']['mean_ms']:.3f}/{series['latency']['p99_ms']:.3f}, wake "
            f"{series['wake']['mean_ms']:.3f}/{series['wake']['p99_ms']:.3f}"
            + (f"\n  loop modes:{modes}" if modes else ""))
