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


#: Published for this long [s] at 20 Hz (as `go2-wbc teleop --dds` does), then nothing.
PUBLISH_S, SPEED_MPS = 2.0, 0.3


@pytest.mark.slow
def test_cmd_vel_across_processes_walks_the_robot_and_its_timeout_stops_it(tmp_path):
    with DdsProcesses(tmp_path, domain_id=private_domain_id(8)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        bridge = run.bridge(log=False)
        controller = run.controller(log=False)
        start = truth.wait_for(standing, timeout_s=15.0, hold_s=0.5, what="the robot standing")
        dds = join_domain(run.interface, domain_id=run.domain_id)
        writer = CmdVelWriter(dds)
        try:
            assert writer.wait_for_reader(10.0)
            end = time.monotonic() + PUBLISH_S
            while time.monotonic() < end:
                writer.publish(SPEED_MPS, 0.0, 0.0)
                time.sleep(0.05)
            moved = truth.latest()
            last_s = float(moved["t_s"])
            # On four loaded feet for 0.5 s of the truth's time: stopped by the timeout.
            rest = truth.wait_for(standing, timeout_s=10.0, hold_s=0.5,
                                  what="the robot standing after the timeout")
        finally:
            writer.close()
            dds.close()
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
        report = json.loads(controller.report_path.read_text())
    forward = float(moved["q"][0] - start["q"][0])
    travelled = float(np.hypot(*(rest["q"][:2] - start["q"][:2])))
    rested_after_s = float(rest["t_s"]) - 0.5 - last_s
    print(f"\ncmd_vel over DDS: {forward:.3f} m forward while publishing {PUBLISH_S:g} s at "
          f"{SPEED_MPS} m/s, {travelled:.3f} m in all; standing again {rested_after_s:.2f} s "
          f"after the last sample; {report['velocity_inputs']}")
    assert forward > 0.25  # walking, not standing still
    assert report["velocity_inputs"]["topic_commands"] >= 20
    assert report["velocity_inputs"]["refused"] == 0
    assert rested_after_s < 0.5 + 1.0  # the timeout, then the stop within 1 s
