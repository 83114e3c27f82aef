"""cmd_vel on DDS (``rt/cmd_vel``, ROS 2's Twist type): the controller's reader in this
process, and across processes: ``go2-wbc bridge``, ``go2-wbc run --dds`` and this test
publishing, the walk and its stop after the timeout seen on the bridge's truth."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from actions.robot.velocity_inputs import VelocityInputs
from benchmarks.dds_outputs import TruthMonitor, standing
from benchmarks.dds_processes import DdsProcesses, private_domain_id, wait_until
from sim.cli.exit_codes import EXIT_INTERRUPTED
from tests.test_wireless_remote import RecordingLoop
from wbc.robot_io.dds.cmd_vel_topic import CmdVelWriter
from wbc.robot_io.dds.domain_config import join_domain


def test_a_command_on_the_topic_reaches_the_loop_and_a_bad_one_is_said_once():
    domain = private_domain_id(7)
    loop, said = RecordingLoop(), []
    inputs = VelocityInputs(loop, domain_id=domain, interface="lo", say=said.append)
    dds = join_domain("lo", domain_id=domain)
    writer = CmdVelWriter(dds)
    try:
        assert writer.wait_for_reader(10.0)
        inputs.poll(0.0)
        assert loop.commands == []  # nothing published yet
        writer.publish(0.3, -0.1, 0.5)
        wait_until(lambda: (inputs.poll(0.0), loop.commands)[1] or None, timeout_s=10.0,
                   what="the command to arrive")
        assert loop.commands == [(0.3, -0.1, 0.5)]
        writer.publish(5.0, 0.0, 0.0)
        wait_until(lambda: (inputs.poll(0.0), inputs.refused)[1] or None, timeout_s=10.0,
                   what="the bad command to arrive")
        assert said == [("rt/cmd_vel: velocity command: forward_mps: expected a velocity in "
                         "[-1, 1] m/s, received 5.0; dropped (said once, counted in the report)")]
        assert inputs.report() == {"topic_commands": 2, "remote_commands": 0, "refused": 1}
    finally:
        writer.close()
        dds.close()
        inputs.close()


#: The walk out and back [m] and its speed [m/s], published at 20 Hz (as `go2-wbc teleop
#: --dds` does) until the truth shows the robot there.
DISTANCE_M, SPEED_MPS = 2.0, 0.5


def walk_to(writer: CmdVelWriter, truth: TruthMonitor, x_m: float, speed_mps: float,
            *, limit_s: float = 30.0) -> float:
    """Publish ``speed_mps`` until the truth's base is past ``x_m``; the truth's time then."""
    end = time.monotonic() + limit_s
    while True:
        record = truth.latest()
        x = float(record["q"][0])
        if (x - x_m) * speed_mps >= 0.0:
            return float(record["t_s"])
        assert time.monotonic() < end, f"not at x = {x_m} m within {limit_s} s (at {x:.3f})"
        writer.publish(speed_mps, 0.0, 0.0)
        time.sleep(0.05)


@pytest.mark.slow
def test_cmd_vel_across_processes_walks_2_m_and_back_and_its_timeout_stops_it(tmp_path):
    """bridge + run --dds + this test publishing rt/cmd_vel: out 2 m, stopped by the
    timeout (no more commands), back to the start, stopped by a zero command."""
    with DdsProcesses(tmp_path, domain_id=private_domain_id(8)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        bridge = run.bridge(log=False)
        controller = run.controller(log=False)
        start = truth.wait_for(standing, timeout_s=15.0, hold_s=0.5, what="the robot standing")
        x0 = float(start["q"][0])
        dds = join_domain(run.interface, domain_id=run.domain_id)
        writer = CmdVelWriter(dds)
        try:
            assert writer.wait_for_reader(10.0)
            last_s = walk_to(writer, truth, x0 + DISTANCE_M, SPEED_MPS)
            # Nothing more is sent: on four loaded feet for 0.5 s, stopped by the timeout.
            out = truth.wait_for(standing, timeout_s=10.0, hold_s=0.5,
                                 what="the robot standing after the timeout")
            walk_to(writer, truth, x0, -SPEED_MPS)
            writer.publish(0.0, 0.0, 0.0)
            back = truth.wait_for(standing, timeout_s=10.0, hold_s=0.5,
                                  what="the robot standing after the zero command")
        finally:
            writer.close()
            dds.close()
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
        report = json.loads(controller.report_path.read_text())
    out_x, back_x = float(out["q"][0]) - x0, float(back["q"][0]) - x0
    drift = float(np.hypot(*(back["q"][:2] - start["q"][:2])))
    rested_after_s = float(out["t_s"]) - 0.5 - last_s
    print(f"\ncmd_vel over DDS at {SPEED_MPS} m/s: out to {out_x:.3f} m (standing "
          f"{rested_after_s:.2f} s after the last command), back to {back_x:+.3f} m, "
          f"{drift:.3f} m from the start; {report['velocity_inputs']}")
    # Past 2 m: the 0.5 s timeout at speed (0.25 m), then the stop's last steps.
    assert DISTANCE_M <= out_x < DISTANCE_M + SPEED_MPS * 0.5 + 0.3
    assert rested_after_s < 0.5 + 1.0  # the timeout, then the stop within 1 s
    assert abs(back_x) < 0.3 and drift < 0.3
    assert report["velocity_inputs"]["topic_commands"] >= 100
    assert report["velocity_inputs"]["refused"] == 0
