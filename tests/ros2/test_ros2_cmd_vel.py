"""``/cmd_vel`` on ``go2-wbc ros2``: a ``geometry_msgs/Twist`` published from this process at
20 Hz walks the simulated GO2 (seen on ``/odom``), and when it stops coming the node's timeout
stops the robot; ``/walk`` is served with the library's Walk type."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from benchmarks.dds_processes import DdsProcesses, wait_until
from tests.ros2.conftest import TopicRecorder

#: Longest wait [s] for the node to start serving (see test_ros2_node).
NODE_TIMEOUT_S = 600.0
#: Published for this long [s] at 20 Hz, then nothing.
PUBLISH_S, SPEED_MPS = 2.0, 0.3


class TwistPublisher:
    """A ``/cmd_vel`` publisher in this process (its own ROS context), as a teleop would.

    Args:
        domain_id: The ROS 2 domain (default: ``ROS_DOMAIN_ID``'s).
        qos: The publisher's QoS (default: depth 10, Reliable, as ``teleop_twist_keyboard``).
    """

    def __init__(self, *, domain_id: int | None = None, qos: object = 10) -> None:
        import rclpy
        from geometry_msgs.msg import Twist
        from rclpy.node import Node

        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, domain_id=domain_id)
        self.node = Node("go2_wbc_test_teleop", context=self.context)
        self.publisher = self.node.create_publisher(Twist, "/cmd_vel", qos)
        self.twist = Twist

    def publish(self, forward_mps: float, lateral_mps: float = 0.0,
                yaw_rate_radps: float = 0.0) -> None:
        message = self.twist()
        message.linear.x, message.linear.y = forward_mps, lateral_mps
        message.angular.z = yaw_rate_radps
        self.publisher.publish(message)

    def close(self) -> None:
        import rclpy

        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture(scope="module")
def node(tmp_path_factory: pytest.TempPathFactory) -> Iterator[DdsProcesses]:
    with DdsProcesses(tmp_path_factory.mktemp("ros2_cmd_vel")) as run:
        process = run.start("node", "ros2")
        process.wait_for_line(r"^ROS 2 node /go2_wbc", timeout_s=NODE_TIMEOUT_S)
        yield run


def test_a_twist_stream_walks_the_robot_and_its_end_stops_it(node: DdsProcesses) -> None:
    from nav_msgs.msg import Odometry

    recorder = TopicRecorder({"/odom": Odometry})
    publisher = TwistPublisher()
    try:
        wait_until(lambda: publisher.publisher.get_subscription_count() or None,
                   timeout_s=30.0, what="the node to subscribe to /cmd_vel")
        recorder.recording = True
        wait_until(lambda: recorder.messages["/odom"] or None, timeout_s=30.0,
                   what="/odom from the node")
        start = recorder.messages["/odom"][-1][1].pose.pose.position.x
        pause = threading.Event()
        end = time.monotonic() + PUBLISH_S
        while time.monotonic() < end:
            publisher.publish(SPEED_MPS)
            pause.wait(0.05)
        stopped_publishing = time.monotonic()
        pause.wait(3.0)
    finally:
        recorder.recording = False
        publisher.close()
        recorder.close()
    odom = recorder.messages["/odom"]
    moved = max(m.pose.pose.position.x for _, m in odom) - start
    late = [m for t, m in odom if t > stopped_publishing + 0.5 + 1.5]
    speeds = [abs(m.twist.twist.linear.x) for m in late]
    print(f"\n/cmd_vel at {SPEED_MPS} m/s for {PUBLISH_S:g} s: {moved:.3f} m on /odom; "
          f"forward speed 2 s after the last message {max(speeds):.3f} m/s at most")
    assert moved > 0.25
    assert late and max(speeds) < 0.05


def test_walk_is_served_with_the_librarys_type(node: DdsProcesses) -> None:
    process = node.start("client", "send-goal", "walk",
                         "{forward_mps: 0.3, duration_s: 1.0}", "--ros2")
    assert process.wait(120.0) == 0, process.tail()
    assert process.output().rstrip().endswith("Goal finished with status: SUCCEEDED")
