"""The GO2's ROS 2 node: the control loop's actions as rclpy action servers, and its state
topics, on an executor spinning in its own threads.

:class:`Go2Node` wraps a control loop (:class:`actions.robot.control_loop.ControlLoop`, on the
simulated GO2 or a GO2 on DDS). Its executor never runs inside the control tick: goals and
cancels reach the runner through its thread-safe entry points
(:mod:`go2_ros2.ros_action_server`), and the tick only copies its estimate for the state
topics (:mod:`go2_ros2.state_publisher`).
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.utilities import get_rmw_implementation_identifier

from go2_ros2.ros_action_server import RosActionServer
from go2_ros2.ros_names import DEFAULT_NODE_NAME, ROS_ACTION_NAMES, ros_action_type
from go2_ros2.state_publisher import StatePublisher

#: Executor threads: a running goal's execute callback holds one while it runs; goal and
#: cancel callbacks wait for the control loop's next tick; the state topics need one.
EXECUTOR_THREADS = 4


class Go2Node:
    """A ROS 2 node serving a control loop's actions and publishing its state.

    Args:
        loop: The control loop (its ``runner``, ``context`` and ``hooks`` are used).
        node_name: The node's name.
        namespace: The node's namespace (``""``: the root).
        ros_args: Arguments after ``--ros-args`` (``["--remap", "high_five:=hf"]``, ...).
        sim_time: The loop runs in simulated time: stamp with it, publish ``/clock`` and set
            the node's ``use_sim_time``.

    Raises:
        rclpy's errors: invalid names or ROS arguments.
    """

    def __init__(self, loop: Any, *, node_name: str = DEFAULT_NODE_NAME, namespace: str = "",
                 ros_args: Sequence[str] = (), sim_time: bool = False) -> None:
        self.context = Context()
        rclpy.init(args=["go2-wbc", "--ros-args", *ros_args], context=self.context)
        overrides = [Parameter("use_sim_time", Parameter.Type.BOOL, True)] if sim_time else []
        try:
            self.node = Node(node_name, namespace=namespace, context=self.context,
                             parameter_overrides=overrides)
            self.servers = [RosActionServer(self.node, loop.runner, local, ros_name,
                                            ros_action_type(local))
                            for local, ros_name in ROS_ACTION_NAMES.items()]
            self.state = StatePublisher(self.node, sim_time=sim_time)
        except BaseException:
            rclpy.try_shutdown(context=self.context)
            raise
        loop.hooks.append(self.state.tick_hook)
        self._loop = loop
        self.executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS,
                                              context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="ros2-executor", daemon=True)

    @property
    def action_names(self) -> list[str]:
        """The served actions' full names, after the namespace and the remapping rules."""
        return [self.node.resolve_topic_name(name) for name in ROS_ACTION_NAMES.values()]

    @property
    def topic_names(self) -> list[str]:
        """The state topics' full names, after the namespace and the remapping rules."""
        return [self.node.resolve_topic_name(name) for name in self.state.topics]

    @property
    def rmw_name(self) -> str:
        """The ROS middleware in use (the extra's wheels: ``rmw_fastrtps_cpp``)."""
        return get_rmw_implementation_identifier()

    def start(self) -> None:
        """Spin the executor in its own thread."""
        self._thread.start()

    def close(self) -> None:
        """Stop the hook and the executor, destroy the node and leave the ROS context."""
        if self.state.tick_hook in self._loop.hooks:
            self._loop.hooks.remove(self.state.tick_hook)
        self.state.close()
        self.executor.shutdown(timeout_sec=2.0)
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        for server in self.servers:
            server.destroy()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass
