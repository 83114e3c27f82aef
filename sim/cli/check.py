"""``go2-wbc check --dds``: listen to a robot's ``rt/lowstate`` for a few seconds, command
nothing, and say what it finds (:mod:`actions.robot.bringup_check`): the first thing to run
on a robot, or a simulator, the project did not write."""

from __future__ import annotations

import argparse
import json
import sys
from typing import IO, Any

from sim.cli.arg_types import float_in, output_file
from sim.cli.dds_options import add_dds_options
from sim.cli.exit_codes import EXIT_NOT_SUCCEEDED, EXIT_SUCCEEDED, EXIT_UNAVAILABLE, EXIT_USAGE
from wbc.core.errors import ConfigurationError

#: Default listening time [s].
LISTEN_S = 3.0

CHECK_HELP = """\
It writes nothing: a robot under another controller (its sport mode) is not disturbed.
It prints, from what the robot sends: the rate and jitter; head, level_flag, CRC and
tick (a GO2, Unitree's C++ or Python simulator, this project's bridge); the joint
positions against the GO2's ranges in the SDK's and the description's orders; the pose
(lying, standing) and whether the robot is still; the IMU's quaternion, tilt, gyroscope
bias and gravity at rest; the foot-force counts; who else writes rt/lowcmd. It ends
with the settings to use, or with what is wrong.

examples:
  go2-wbc check --dds                          # the simulator bridge: domain 1 on lo
  go2-wbc check --dds --domain 0 --interface eth0 --seconds 5 --report check.json

exit status:
    0  a robot streams and nothing must be dealt with first (the settings are printed)
    1  a robot streams, with a problem to deal with first (each is printed)
    2  bad arguments (the message names the argument and what is valid)
    4  no robot streams rt/lowstate on this domain and interface
"""


def add_check_command(sub: Any) -> None:
    """Add ``check`` to the ``go2-wbc`` subcommands."""
    check = sub.add_parser(
        "check", help="listen to a robot on DDS without commanding it and say what it finds "
                      "(go2-wbc check --dds)",
        description="Listen to a robot's rt/lowstate on DDS for a few seconds, without\n"
                    "commanding it, and print what it finds and the settings to use.",
        epilog=CHECK_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    robot = check.add_argument_group("robot")
    add_dds_options(robot, flag_help="listen to a robot over DDS (required, no default: "
                                     "the check only listens on DDS)")
    robot.add_argument("--seconds", type=float_in(0.5, 600.0, what="a time", unit="s",
                                                  fmt="g"),
                       default=LISTEN_S, metavar="S",
                       help=f"how long to listen [s] (default: {LISTEN_S:g})")
    check.add_argument("--report", type=output_file(".json"), metavar="FILE.json",
                       help="write the findings and figures as JSON (default: none)")
    check.set_defaults(run=run_check, parser=check)


def run_check(args: argparse.Namespace, *, stream: IO[str] | None = None) -> int:
    """``go2-wbc check --dds``; returns the exit status."""
    if not args.dds:
        args.parser.error("--dds: required ('check' listens to a robot over DDS)")
    from actions.robot.bringup_check import check_stream
    from wbc.robot_io.dds.state_listener import StateListener

    out = stream or sys.stdout
    try:
        with StateListener(domain_id=args.domain, interface=args.interface) as listener:
            out.write(f"listening to rt/lowstate on DDS domain {args.domain} (interface "
                      f"{args.interface}) for {args.seconds:g} s; commanding nothing\n")
            out.flush()
            heard = listener.listen(args.seconds)
    except ConfigurationError as err:
        print(f"go2-wbc: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    report = check_stream(heard)
    for line in report.lines():
        out.write(line + "\n")
    if args.report is not None:
        args.report.write_text(json.dumps({
            "ok": report.ok, "domain": args.domain, "interface": args.interface,
            "findings": [vars(f) for f in report.findings], "figures": report.figures,
            "settings": report.settings}, indent=2, default=str) + "\n")
        out.write(f"report: {args.report}\n")
    if report.figures.get("states", 0) < 10 and not report.ok:
        return EXIT_UNAVAILABLE
    return EXIT_SUCCEEDED if report.ok else EXIT_NOT_SUCCEEDED
