"""``go2-wbc teleop``: walk the GO2 from the keyboard, in a terminal (raw mode).

Without ``--dds`` it drives the simulated GO2 on the wall clock (as ``go2-wbc ros2`` does),
its loop on a thread of its own and the keys on this one, through the loop's velocity stream
(:meth:`~actions.robot.control_loop.ControlLoop.command_velocity`). With ``--dds`` it
publishes ``rt/cmd_vel`` for a ``go2-wbc run --dds`` process. Either way the command is sent
at ``--rate`` (20 Hz) while teleop runs, so the controller's timeout stops the robot only when
teleop stops sending; it prints the commanded and the measured velocity (the simulated loop's
estimate, or with ``--dds`` the bridge's truth on ``rt/wbc/sim/truth`` when there is one).
Keys: :mod:`sim.cli.teleop_keys`.
"""

from __future__ import annotations

import argparse
import os
import select
import sys
import termios
import threading
import time
from collections.abc import Callable
from typing import IO, Any

import numpy as np

from sim.cli.arg_types import float_in
from sim.cli.dds_options import add_dds_options
from sim.cli.exit_codes import EXIT_SUCCEEDED, EXIT_USAGE
from sim.cli.teleop_keys import KEYS_HELP, KeyTeleop
from sim.gait_view import heading_velocities
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS

#: Control rates [Hz] of the simulated robot.
RATES_HZ = (1000, 500)
#: How often [Hz] the status line is rewritten.
STATUS_HZ = 5.0

TELEOP_HELP = f"""\
{KEYS_HELP}.

examples:
  go2-wbc teleop                         # the simulated GO2, on the wall clock
  go2-wbc bridge &  go2-wbc run --dds &  # the simulated GO2 on DDS and its controller,
  go2-wbc teleop --dds                   # then teleop publishing rt/cmd_vel

each key press changes the command by one step and the command is held (sent at --rate)
until changed; space stops. When teleop exits, or stops sending, the controller stops the
robot on four feet after the command's timeout (0.5 s by default).
"""


def add_teleop_command(sub: Any) -> None:
    """Add ``teleop`` to the ``go2-wbc`` subcommands."""
    teleop = sub.add_parser(
        "teleop", help="walk the GO2 from the keyboard (the simulated one, or --dds)",
        description="Walk the GO2 from the keyboard, in a terminal: the simulated GO2 on the "
                    "wall clock, or with --dds a 'go2-wbc run --dds' process (rt/cmd_vel).",
        epilog=TELEOP_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    robot = teleop.add_argument_group("robot")
    add_dds_options(robot, flag_help="publish rt/cmd_vel for a 'go2-wbc run --dds' process "
                                     "(default: drive the simulated GO2 here)")
    robot.add_argument("--plant", dest="sim_plant", choices=tuple(PLANT_PRESETS),
                       default=DEFAULT_PLANT,
                       help=f"the simulated plant (default: {DEFAULT_PLANT}; not with --dds)")
    robot.add_argument("--control-rate", type=int, choices=RATES_HZ, default=RATES_HZ[0],
                       metavar="HZ", help="the simulated robot's control rate [Hz]: 1000 or "
                                          "500 (default: 1000; not with --dds)")
    robot.add_argument("--rate", type=float_in(5.0, 100.0, what="a rate", unit="Hz", fmt="g"),
                       default=20.0, metavar="HZ",
                       help="how often the command is sent [Hz] (default: 20)")
    teleop.set_defaults(run=run_teleop, parser=teleop)


def run_teleop(args: argparse.Namespace, *, stdin: IO[str] | None = None,
               stream: IO[str] | None = None) -> int:
    """``go2-wbc teleop``; returns the exit status."""
    keyboard = stdin or sys.stdin
    out = stream or sys.stdout
    if not keyboard.isatty():
        print("go2-wbc teleop: error: stdin is not a terminal: teleop reads keys from one "
              "(from a program, publish rt/cmd_vel or call ControlLoop.command_velocity)",
              file=sys.stderr)
        return EXIT_USAGE
    if args.dds and (args.sim_plant != DEFAULT_PLANT or args.control_rate != RATES_HZ[0]):
        args.parser.error("--plant, --control-rate: simulation options, not used with --dds")
    target = DdsTarget(args.domain, args.interface) if args.dds else SimTarget(
        args.sim_plant, args.control_rate)
    try:
        say = _Say(out)
        say(target.describe())
        say(KEYS_HELP)
        keys = KeyTeleop(target.limits)
        with RawTerminal(keyboard.fileno()):
            _session(keys, target, keyboard.fileno(), say, period_s=1.0 / args.rate)
        say(target.stop())
    finally:
        target.close()
    return EXIT_SUCCEEDED


def _session(keys: KeyTeleop, target: Any, fd: int, say: _Say, *, period_s: float) -> None:
    """Read keys until a quit key, sending the command every ``period_s`` [s] (wall clock)
    and rewriting the status line at :data:`STATUS_HZ`."""
    next_send = next_status = time.monotonic()
    while not keys.quit:
        wait = max(0.0, min(next_send, next_status) - time.monotonic())
        readable, _, _ = select.select([fd], [], [], wait)
        if readable:
            data = os.read(fd, 64)
            if not data:  # the terminal closed
                break
            before = keys.command
            keys.handle(data)
            if keys.command != before:
                next_send = time.monotonic()  # a change goes out at once
        now = time.monotonic()
        if now >= next_send:
            target.send(keys.command)
            next_send = now + period_s
        if now >= next_status:
            say.status(_status(keys.command, target.measured()))
            next_status = now + 1.0 / STATUS_HZ


def _status(command: tuple[float, float, float],
            measured: tuple[float, float, float] | None) -> str:
    """The status line: commanded and measured velocity."""
    text = (f"command: forward {command[0]:+.2f} m/s, left {command[1]:+.2f} m/s, yaw "
            f"{command[2]:+.2f} rad/s | measured: ")
    if measured is None:
        return text + "-"
    return (text + f"forward {measured[0]:+.2f} m/s, left {measured[1]:+.2f} m/s, yaw "
            f"{measured[2]:+.2f} rad/s")


def heading_velocity(q: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
    """Forward and leftward [m/s] and the yaw rate [rad/s] of the base in its heading frame
    (:func:`sim.gait_view.heading_velocities` of one state), as the line prints them."""
    forward, left, yaw_rate = heading_velocities(q, v).tolist()
    return forward, left, yaw_rate


class SimTarget:
    """The simulated GO2 on the wall clock, its loop on a thread of its own."""

    def __init__(self, plant: str, rate_hz: int) -> None:
        from go2_ros2.paced_loop import PacedLoop
        from sim.control_loop import ControlLoop

        self.loop = ControlLoop.simulated(plant=plant, control_period_s=1.0 / rate_hz)
        self.limits = self.loop.context.velocity_stream.limits
        self._rate_hz = rate_hz
        self._paced = PacedLoop(self.loop)
        self._thread = threading.Thread(target=self._paced.run, name="go2-wbc teleop loop",
                                        daemon=True)
        self._thread.start()

    def describe(self) -> str:
        return (f"teleop: the simulated GO2 at {self._rate_hz} Hz on the wall clock (its "
                "estimate is the measured velocity)")

    def send(self, command: tuple[float, float, float]) -> None:
        self.loop.command_velocity(*command)

    def measured(self) -> tuple[float, float, float] | None:
        context = self.loop.context
        return heading_velocity(context.q, context.v)

    def stop(self) -> str:
        """Stop walking, wait (at most 3 s) for the walk to end; a summary line."""
        stream = self.loop.context.velocity_stream
        self.loop.command_velocity(0.0, 0.0, 0.0)
        end = time.monotonic() + 3.0
        while stream.walking and time.monotonic() < end:
            time.sleep(0.01)
        q, _ = self.loop.true_state()
        return (f"stopped at {self.loop.robot.time_s:.1f} s of simulated time, "
                f"{'still walking' if stream.walking else 'standing'}; base at "
                f"({q[0]:+.2f}, {q[1]:+.2f}) m in the truth")

    def close(self) -> None:
        self._paced.request_stop()
        self._thread.join(timeout=5.0)


class DdsTarget:
    """A ``go2-wbc run --dds`` process: ``rt/cmd_vel`` published, the bridge's truth read."""

    def __init__(self, domain_id: int, interface: str) -> None:
        from wbc.locomotion.gait import VelocityLimits
        from wbc.robot_io.dds.cmd_vel_topic import CmdVelWriter
        from wbc.robot_io.dds.domain_config import join_domain
        from wbc.robot_io.dds.sdk_qos import sdk_reader_qos
        from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC, SimTruthMessage
        from wbc.robot_io.dds.topic_endpoints import TopicReader

        self.limits = VelocityLimits()
        self._where = f"DDS domain {domain_id} (interface {interface})"
        self._dds = join_domain(interface, domain_id=domain_id)
        self._writer = CmdVelWriter(self._dds)
        self._truth = TopicReader(self._dds, SIM_TRUTH_TOPIC, SimTruthMessage,
                                  qos=sdk_reader_qos())
        self._measured: tuple[float, float, float] | None = None

    def describe(self) -> str:
        return (f"teleop: publishing rt/cmd_vel on {self._where} for 'go2-wbc run --dds' "
                "(measured: the bridge's truth, rt/wbc/sim/truth, when it publishes one)")

    def send(self, command: tuple[float, float, float]) -> None:
        self._writer.publish(*command)

    def measured(self) -> tuple[float, float, float] | None:
        sample = self._truth.take_newest()
        if sample is not None:
            record = sample.record
            self._measured = heading_velocity(record["q"], record["v"])
        return self._measured

    def readers(self) -> int:
        """How many controllers read ``rt/cmd_vel`` now."""
        return self._writer.matched_readers()

    def stop(self) -> str:
        self._writer.publish(0.0, 0.0, 0.0)
        readers = self.readers()
        return (f"sent a stop; {readers} controller(s) reading rt/cmd_vel" if readers else
                "sent a stop, but no controller reads rt/cmd_vel (is 'go2-wbc run --dds' "
                f"running on {self._where}?)")

    def close(self) -> None:
        self._truth.close()
        self._writer.close()
        self._dds.close()


class _Say:
    """Lines and a status line rewritten in place, in a terminal in raw mode (``\\r\\n``)."""

    def __init__(self, out: IO[str]) -> None:
        self._out = out
        self._status = False

    def __call__(self, line: str) -> None:
        self._out.write(("\r\n" if self._status else "") + line + "\r\n")
        self._status = False
        self._out.flush()

    def status(self, line: str) -> None:
        self._out.write("\r\x1b[K" + line)
        self._status = True
        self._out.flush()


class RawTerminal:
    """The terminal on ``fd`` in raw mode (keys one at a time, no echo, Ctrl-C as a key)
    while the block runs; restored after, whatever happens."""

    def __init__(self, fd: int, setter: Callable[..., None] = termios.tcsetattr) -> None:
        self._fd = fd
        self._set = setter
        self._saved: list[Any] = []

    def __enter__(self) -> None:
        self._saved = termios.tcgetattr(self._fd)
        raw = termios.tcgetattr(self._fd)
        raw[3] &= ~(termios.ICANON | termios.ECHO | termios.ISIG | termios.IEXTEN)  # lflag
        raw[6][termios.VMIN], raw[6][termios.VTIME] = 0, 0
        self._set(self._fd, termios.TCSADRAIN, raw)

    def __exit__(self, *exc: object) -> None:
        self._set(self._fd, termios.TCSADRAIN, self._saved)
