"""``go2-wbc teleop``: the key map, the measured velocity's frame, and the refusals."""

from __future__ import annotations

import io
import math

import numpy as np
import pytest

from sim.cli import main
from sim.cli.exit_codes import EXIT_USAGE
from sim.cli.teleop import heading_velocity
from sim.cli.teleop_keys import KeyTeleop, key_names
from wbc.locomotion.gait import VelocityLimits


def test_key_names_split_arrow_sequences_from_letters():
    assert key_names(b"w\x1b[A\x1bOBq \x1b[C\x1b[Dx\x03") == [
        "w", "up", "down", "q", " ", "right", "left", "x", "\x03"]
    assert key_names(b"W\x1b[Z") == ["w", "esc", "[", "z"]  # an unknown sequence: nothing


def teleop() -> KeyTeleop:
    return KeyTeleop(VelocityLimits(forward_mps=1.0, lateral_mps=0.4, yaw_rate_radps=1.2))


@pytest.mark.parametrize("keys, command", [
    (b"w", (0.1, 0.0, 0.0)), (b"\x1b[A\x1b[A", (0.2, 0.0, 0.0)), (b"s", (-0.1, 0.0, 0.0)),
    (b"\x1b[Bs", (-0.2, 0.0, 0.0)), (b"a", (0.0, 0.1, 0.0)), (b"dd", (0.0, -0.2, 0.0)),
    (b"q", (0.0, 0.0, 0.2)), (b"\x1b[D", (0.0, 0.0, 0.2)), (b"e\x1b[C", (0.0, 0.0, -0.4)),
    (b"wwaq ", (0.0, 0.0, 0.0)), (b"wwx", (0.0, 0.0, 0.0)), (b"wsws", (0.0, 0.0, 0.0)),
    (b"zZ1?", (0.0, 0.0, 0.0)),
])
def test_each_key_steps_its_component_and_space_stops(keys, command):
    keys_state = teleop()
    assert keys_state.handle(keys) is True
    assert keys_state.command == command


def test_the_command_stays_on_its_grid_and_within_the_limits():
    keys_state = teleop()
    keys_state.handle(b"w" * 37)
    assert keys_state.command == (1.0, 0.0, 0.0)  # 3.7 m/s asked, 1.0 the limit
    keys_state.handle(b"s" * 13)
    assert keys_state.command == (-0.3, 0.0, 0.0)  # exactly, not -0.30000000000000004
    keys_state.handle(b"a" * 9 + b"e" * 9)
    assert keys_state.command == (-0.3, 0.4, -1.2)


@pytest.mark.parametrize("quit_key", [b"\x03", b"\x04"])
def test_ctrl_c_or_ctrl_d_quits_with_a_stop(quit_key):
    keys_state = teleop()
    assert keys_state.handle(b"ww" + quit_key + b"w") is False
    assert keys_state.quit and keys_state.command == (0.0, 0.0, 0.0)


def test_the_measured_velocity_is_in_the_heading_frame():
    q = np.zeros(19)
    yaw = math.radians(90.0)
    q[3:7] = [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]  # facing +y
    v = np.zeros(18)
    v[:6] = [0.5, 0.1, 0.0, 0.0, 0.0, 0.3]  # base frame: forward, left; yaw rate
    assert heading_velocity(q, v) == pytest.approx((0.5, 0.1, 0.3))
    roll = math.radians(10.0)  # rolled: the base's y axis tilts, the heading does not
    q[3:7] = [math.sin(roll / 2), 0.0, 0.0, math.cos(roll / 2)]
    forward, left, yaw_rate = heading_velocity(q, v)
    assert (forward, left) == pytest.approx((0.5, 0.1 * math.cos(roll)))
    assert yaw_rate == pytest.approx(0.3 * math.cos(roll))


class FakeTerminal(io.StringIO):
    """Says it is a terminal (the option checks come after the terminal's)."""

    def isatty(self) -> bool:
        return True


def test_without_a_terminal_it_says_so_in_one_line_and_exits_2(capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    assert main(["teleop"]) == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (
        "go2-wbc teleop: error: stdin is not a terminal: teleop reads keys from one (from a "
        "program, publish rt/cmd_vel or call ControlLoop.command_velocity)\n")


@pytest.mark.parametrize("argv, message", [
    (["--rate", "500"], "--rate: expected a rate in [5, 100] Hz, received 500"),
    (["--plant", "wood"], ("--plant: invalid choice: 'wood' (choose from 'menagerie', "
                           "'unitree-mujoco', 'identified', 'ideal')")),
    (["--dds", "--plant", "ideal"], ("--plant, --control-rate: simulation options, not used "
                                    "with --dds")),
])
def test_bad_options_are_one_line_naming_the_option(capsys, monkeypatch, argv, message):
    monkeypatch.setattr("sys.stdin", FakeTerminal())
    with pytest.raises(SystemExit) as info:
        main(["teleop", *argv])
    assert info.value.code == EXIT_USAGE
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"go2-wbc teleop: error: {message} (see 'go2-wbc teleop --help')")


@pytest.mark.slow
def test_teleop_in_a_pseudo_terminal_walks_the_simulated_go2_and_quits_standing():
    """The command as a user runs it: keys through a terminal in raw mode, the simulated
    GO2 on the wall clock; three presses of w, a stop, Ctrl-C."""
    import os
    import pty
    import select
    import sys
    import time

    pid, fd = pty.fork()
    if pid == 0:  # the child: go2-wbc teleop on the pseudo-terminal
        os.execv(sys.executable, [sys.executable, "-m", "sim.cli", "teleop"])
    output = bytearray()

    def read_until(pattern: bytes | None, timeout_s: float) -> None:
        """Read the child's output until ``pattern`` came (``None``: for ``timeout_s``)."""
        end = time.monotonic() + timeout_s
        while pattern is None or pattern not in output:
            if time.monotonic() >= end:
                assert pattern is None, f"no {pattern!r} in {bytes(output[-2000:])!r}"
                return
            if select.select([fd], [], [], 0.05)[0]:
                try:
                    output.extend(os.read(fd, 4096))
                except OSError:  # the child closed the terminal
                    return

    try:
        read_until(b"| measured:", 180.0)  # started: the first status line
        os.write(fd, b"www")
        read_until(b"command: forward +0.30", 10.0)
        mark = len(output)
        read_until(None, 4.0)  # the walk starts and settles at its speed
        walking = bytes(output[mark:]).split(b"\r\x1b[K")
        os.write(fd, b" ")
        read_until(None, 2.0)
        os.write(fd, b"\x03")
        read_until(b"stopped at", 30.0)
        _, status = os.waitpid(pid, 0)
        read_until(b"in the truth", 5.0)
    finally:
        try:
            os.kill(pid, 9)
        except ProcessLookupError:
            pass
        os.close(fd)
    assert os.waitstatus_to_exitcode(status) == 0, bytes(output[-2000:])
    speeds = [float(line.split(b"measured: forward ")[1].split(b" ")[0])
              for line in walking[-8:] if b"measured: forward " in line]
    print(f"\nteleop at 0.3 m/s: measured forward {speeds} m/s; "
          f"{bytes(output).split(b'stopped at')[1][:120]!r}")
    assert speeds and all(0.15 < speed < 0.45 for speed in speeds)
    assert b", standing; base at (+" in output  # walked forward, then stood


def test_teleop_dds_publishes_rt_cmd_vel_and_says_who_reads_it():
    from benchmarks.dds_processes import private_domain_id, wait_until
    from sim.cli.teleop import DdsTarget
    from wbc.robot_io.dds.cmd_vel_topic import CmdVelReader
    from wbc.robot_io.dds.domain_config import join_domain

    domain = private_domain_id(11)
    target = DdsTarget(domain, "lo")
    try:
        assert target.stop() == (  # nobody reads yet
            f"sent a stop, but no controller reads rt/cmd_vel (is 'go2-wbc run --dds' "
            f"running on DDS domain {domain} (interface lo)?)")
        dds = join_domain("lo", domain_id=domain)
        reader = CmdVelReader(dds)
        try:
            wait_until(lambda: target.readers() or None, timeout_s=10.0,
                       what="the reader to match")
            target.send((0.3, -0.1, 0.4))
            taken = wait_until(reader.take, timeout_s=10.0, what="the command")
            assert taken == pytest.approx((0.3, -0.1, 0.4))
            assert target.measured() is None  # no bridge publishes the truth here
            assert target.stop() == "sent a stop; 1 controller(s) reading rt/cmd_vel"
        finally:
            reader.close()
            dds.close()
    finally:
        target.close()
