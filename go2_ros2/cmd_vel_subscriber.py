"""``/cmd_vel`` (``geometry_msgs/Twist``) into the control loop's velocity stream: ``linear.x``
forward, ``linear.y`` leftward [m/s], ``angular.z`` the turning rate [rad/s] (the base's
heading frame); the other three components are ignored.

The subscription is BestEffort, depth 1, which matches Reliable publishers
(``teleop_twist_keyboard``, ``ros2 topic pub``) and BestEffort ones alike; its callback runs
on the node's executor and hands the command to the loop's thread-safe
:meth:`~actions.robot.control_loop.ControlLoop.command_velocity`, which the control tick
picks up. A command beyond the walking limits is dropped and logged (at most once a second),
naming the field, the value and the range.
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import Twist
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

from wbc.core.errors import ConfigurationError

#: The topic, relative (the node's namespace applies).
CMD_VEL_TOPIC = "cmd_vel"


class CmdVelSubscriber:
    """Subscribes ``node`` to :data:`CMD_VEL_TOPIC` for ``loop``.

    Args:
        node: The GO2's node.
        loop: The control loop (its ``command_velocity``).
    """

    def __init__(self, node: Node, loop: Any) -> None:
        self._node = node
        self._loop = loop
        qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
        self.subscription = node.create_subscription(Twist, CMD_VEL_TOPIC, self._received, qos)
        #: Commands received, and those dropped (beyond the limits).
        self.received = 0
        self.dropped = 0

    def _received(self, message: Twist) -> None:
        self.received += 1
        try:
            self._loop.command_velocity(message.linear.x, message.linear.y, message.angular.z)
        except ConfigurationError as err:
            self.dropped += 1
            self._node.get_logger().warning(f"/cmd_vel dropped: {err}",
                                            throttle_duration_sec=1.0)

    def destroy(self) -> None:
        """Remove the subscription from the node."""
        self._node.destroy_subscription(self.subscription)
