"""The streaming velocity command on DDS: ROS 2's ``geometry_msgs/Twist`` as its DDS type
(``geometry_msgs::msg::dds_::Twist_``) on ``rt/cmd_vel``, the DDS name of ROS 2's ``/cmd_vel``.

``linear.x`` forward and ``linear.y`` leftward [m/s], ``angular.z`` the turning rate [rad/s],
counter-clockwise, in the base's heading frame; the other three are ignored. A ``Twist`` has no
stamp: the controller times a command from its arrival (the timeout of
:mod:`actions.go2.velocity_stream`).

:class:`CmdVelReader` (the controller's end: BestEffort, KeepLast 1, which matches Reliable
and BestEffort writers alike) and :class:`CmdVelWriter` (a teleop's end: Reliable, KeepLast 1).

A ROS 2 node's ``/cmd_vel`` publisher (rclpy on Fast DDS, Reliable or BestEffort) matches the
reader as it is, on ``ROS_DOMAIN_ID`` equal to the domain id; on a loopback interface the
node needs ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST`` (or ``ROS_STATIC_PEERS=127.0.0.1``):
with ROS 2's default range it announces itself by multicast, which the participants on
``lo`` do not use (docs/dds.md, "A ROS 2 node on `rt/cmd_vel`";
``tests/ros2/test_ros2_cmd_vel_dds.py``).
"""

# No `from __future__ import annotations`: cyclonedds resolves the field types from the real
# annotation objects.
from dataclasses import dataclass, field

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct

from wbc.robot_io.dds.domain_config import DomainHandle
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos, sdk_writer_qos
from wbc.robot_io.dds.topic_endpoints import TopicReader, TopicWriter

#: The topic (ROS 2's ``/cmd_vel`` on DDS).
CMD_VEL_TOPIC = "rt/cmd_vel"


@dataclass
class Vector3(IdlStruct, typename="geometry_msgs::msg::dds_::Vector3_"):
    """ROS 2's ``geometry_msgs/Vector3`` on DDS."""

    x: t.float64 = 0.0
    y: t.float64 = 0.0
    z: t.float64 = 0.0


@dataclass
class Twist(IdlStruct, typename="geometry_msgs::msg::dds_::Twist_"):
    """ROS 2's ``geometry_msgs/Twist`` on DDS: ``linear`` [m/s], ``angular`` [rad/s]."""

    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)


class CmdVelReader:
    """The controller's reader of ``rt/cmd_vel``.

    Args:
        dds: The domain joined.
    """

    def __init__(self, dds: DomainHandle) -> None:
        self._reader = TopicReader(dds, CMD_VEL_TOPIC, Twist, qos=sdk_reader_qos())

    def take(self) -> tuple[float, float, float] | None:
        """The newest command since the last call as ``(forward_mps, lateral_mps,
        yaw_rate_radps)``, or ``None`` when none came; without blocking."""
        sample = self._reader.take_newest()
        if sample is None:
            return None
        return float(sample.linear.x), float(sample.linear.y), float(sample.angular.z)

    def close(self) -> None:
        """Delete the reader; idempotent."""
        self._reader.close()


class CmdVelWriter:
    """A writer of ``rt/cmd_vel`` (a teleop's end).

    Args:
        dds: The domain joined.
    """

    def __init__(self, dds: DomainHandle) -> None:
        self._writer = TopicWriter(dds, CMD_VEL_TOPIC, Twist, qos=sdk_writer_qos())

    def publish(self, forward_mps: float, lateral_mps: float, yaw_rate_radps: float) -> None:
        """Publish one command (heading frame)."""
        self._writer.write(Twist(linear=Vector3(forward_mps, lateral_mps, 0.0),
                                 angular=Vector3(0.0, 0.0, yaw_rate_radps)))

    def matched_readers(self) -> int:
        """How many readers (controllers) are matched."""
        return self._writer.matched_readers()

    def wait_for_reader(self, timeout_s: float) -> bool:
        """Wait until a reader is matched, at most ``timeout_s`` [s]; whether one is."""
        return self._writer.wait_for_reader(timeout_s)

    def close(self) -> None:
        """Delete the writer; idempotent."""
        self._writer.close()
