"""``rt/cmd_vel`` against real ROS 2: an rclpy node (the extra's wheels: Fast DDS) publishing
``geometry_msgs/Twist`` on ``/cmd_vel`` reaches the controller's own Cyclone DDS reader
(:class:`wbc.robot_io.dds.cmd_vel_topic.CmdVelReader`) with no ROS 2 in the controller: in
this process (both QoS a teleop uses), and across processes, where it walks the simulated GO2
of ``go2-wbc bridge`` driven by ``go2-wbc run --dds`` (without ``--ros2``), and its timeout
stops it on four feet, judged on the bridge's truth.

The ROS 2 side runs on the DDS domain of the controller (``rclpy.init(domain_id=...)``: a
ROS 2 domain is a DDS domain) with ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (set by the
conftest; what a node on the simulator's machine needs: docs/ros2.md, "/cmd_vel to run --dds").
"""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path

import numpy as np

from benchmarks.dds_outputs import TruthMonitor, standing
from benchmarks.dds_processes import (
    CONTROLLER_READY,
    DdsProcesses,
    private_domain_id,
    wait_until,
)
from sim.cli.exit_codes import EXIT_INTERRUPTED
from sim.gait_view import heading_rad, heading_velocities
from tests.ros2.test_ros2_cmd_vel import TwistPublisher
from wbc.robot_io.dds.cmd_vel_topic import CmdVelReader
from wbc.robot_io.dds.domain_config import join_domain

#: Published for this long [s] at this rate [Hz] and speed [m/s], then nothing.
PUBLISH_S, RATE_HZ, SPEED_MPS = 2.0, 20.0, 0.3
#: The controller's timeout of a velocity stream [s] (actions.go2.velocity_stream).
TIMEOUT_S = 0.5
#: Longest wait [s] for ROS 2 and Cyclone DDS to discover each other.
DISCOVERY_S = 30.0
#: Longest wait [s] for the controller to control: numba compiles its kernels first when its
#: cache is cold (after a kernel changed: 2 min and more on the loaded 2-core machine), as the
#: node's wait in test_ros2_cmd_vel.
START_S = 600.0


def test_an_rclpy_twist_reaches_the_controller_s_reader_with_either_qos() -> None:
    """Reliable (depth 10, as ``teleop_twist_keyboard`` and ``ros2 topic pub``) and
    BestEffort (the sensor-data profile) publishers: linear.x, linear.y, angular.z arrive as
    published; the rclpy graph counts the Cyclone reader as a ``/cmd_vel`` subscription."""
    from rclpy.qos import qos_profile_sensor_data

    domain = private_domain_id(11)
    dds = join_domain("lo", domain_id=domain)
    reader = CmdVelReader(dds)
    try:
        for k, qos in enumerate((10, qos_profile_sensor_data)):
            publisher = TwistPublisher(domain_id=domain, qos=qos)
            try:
                wait_until(lambda p=publisher: p.publisher.get_subscription_count() or None,
                           timeout_s=DISCOVERY_S, what="rclpy to discover the Cyclone reader")
                sent, seen = (0.25 + 0.1 * k, -0.1, 0.5), []

                def received(p: TwistPublisher = publisher, sent=sent, seen=seen):
                    p.publish(*sent)  # until discovery completes the other way too
                    sample = reader.take()
                    if sample is not None:
                        seen.append(sample)
                    # The previous publisher's last Twists may still be in flight.
                    return sample if sample == sent else None

                wait_until(received, timeout_s=DISCOVERY_S, poll_s=0.05,
                           what=f"the Twist {sent} to arrive",
                           context=lambda seen=seen: f"received instead: {seen[-5:]}")
                assert all(s in {sent, (0.25 + 0.1 * (k - 1), -0.1, 0.5)} for s in seen), seen
            finally:
                publisher.close()
    finally:
        reader.close()
        dds.close()


def test_an_rclpy_cmd_vel_walks_run_dds_and_its_timeout_stops_it(tmp_path: Path) -> None:
    with DdsProcesses(tmp_path, domain_id=private_domain_id(12)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        bridge = run.bridge(log=False)
        controller = run.controller(log=False, wait=False)
        controller.wait_for_line(CONTROLLER_READY, timeout_s=START_S)
        start = truth.wait_for(standing, timeout_s=15.0, hold_s=0.5, what="the robot standing")
        created_s = time.monotonic()
        publisher = TwistPublisher(domain_id=run.domain_id)
        samples: list[np.ndarray] = []
        try:
            wait_until(lambda: publisher.publisher.get_subscription_count() or None,
                       timeout_s=DISCOVERY_S, what="rclpy to discover run --dds's reader")
            matched_s = time.monotonic()
            pause = threading.Event()
            end = time.monotonic() + PUBLISH_S
            while time.monotonic() < end:
                publisher.publish(SPEED_MPS)
                samples.append(truth.latest())
                pause.wait(1.0 / RATE_HZ)
            publisher.publish(SPEED_MPS)
            last = truth.latest()
            # Nothing more is sent: the timeout, then the stop on four loaded feet.
            rest = truth.wait_for(standing, timeout_s=10.0, hold_s=0.5,
                                  what="the robot standing after the timeout")
        finally:
            publisher.close()
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
        report = json.loads(controller.report_path.read_text())
    x0 = float(start["q"][0])
    during = float(last["q"][0]) - x0
    at_rest = float(rest["q"][0]) - x0
    rested_after_s = float(rest["t_s"]) - 0.5 - float(last["t_s"])
    # The mean forward speed over the second half of the publishing, once walking.
    half = [s for s in samples if float(s["t_s"]) >= float(last["t_s"]) - PUBLISH_S / 2]
    speed = float(np.mean([heading_velocities(s["q"], s["v"])[0] for s in half]))
    yaw_deg = math.degrees(heading_rad(rest["q"]) - heading_rad(start["q"]))
    inputs = report["velocity_inputs"]
    print(f"\nrclpy /cmd_vel at {SPEED_MPS} m/s, {RATE_HZ:g} Hz for {PUBLISH_S:g} s to run --dds "
          f"(matched {matched_s - created_s:.2f} s after the node's start): {during:.3f} m "
          f"while it came, forward {speed:.3f} m/s over its last "
          f"{PUBLISH_S / 2:g} s; standing {rested_after_s:.2f} s after the last one at "
          f"{at_rest:.3f} m, turned {yaw_deg:+.2f} deg; {inputs}")
    assert during > 0.25  # 0.6 m at the command, less the ramp and the first steps
    assert 0.5 * SPEED_MPS < speed < 1.5 * SPEED_MPS
    assert at_rest >= during and at_rest < during + SPEED_MPS * TIMEOUT_S + 0.3
    assert rested_after_s < TIMEOUT_S + 1.0  # the timeout, then the stop within 1 s
    assert inputs["topic_commands"] >= 0.75 * PUBLISH_S * RATE_HZ
    assert inputs["refused"] == 0
    assert abs(yaw_deg) < 5.0
