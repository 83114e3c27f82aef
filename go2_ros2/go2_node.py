"""The GO2's ROS 2 node: the control loop's actions as rclpy action servers, its state
topics, and ``/cmd_vel`` into its velocity stream, on an executor spinning in its own threads.

:class:`Go2Node` wraps a control loop (:class:`actions.robot.control_loop.ControlLoop`, on the
simulated GO2 or a GO2 on DDS). Its executor never runs inside the control tick: goals and
cancels reach the runner through its thread-safe entry points
(:mod:`go2_ros2.ros_action_server`), and the tick only copies its estimate for the state
topics (:mod:`go2_ros2.state_publisher`).
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import partial
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.utilities import get_rmw_implementation_identifier

from go2_ros2.cmd_vel_subscriber import CmdVelSubscriber
from go2_ros2.ros_action_server import RosActionServer
from go2_ros2.ros_names import DEFAULT_NODE_NAME, ROS_ACTION_NAMES, ros_action_type
from go2_ros2.state_publisher import StatePublisher

#: Executor threads: a running goal's execute callback holds one while it runs; goal and
#: cancel callbacks wait for the control loop's next tick.
EXECUTOR_THREADS = 4
#: The interpreter's thread switch interval [s] while the node runs. Python's default, 5 ms,
#: is how long the control loop may wait for the interpreter a ROS 2 thread holds: longer
#: than a 500 Hz period. Measured with run --dds --ros2 on the loaded 2-core machine.
SWITCH_INTERVAL_S = 2e-4


class Go2Node:
    """A ROS 2 node serving a control loop's actions and publishing its state.

    Args:
        loop: The control loop (its ``runner``, ``context`` and ``hooks`` are used).
        node_name: The node's name.
        namespace: The node's namespace (``""``: the root).
        ros_args: Arguments after ``--ros-args`` (``["--remap", "high_five:=hf"]``, ...).
        sim_time: The loop runs in simulated time: stamp with it, publish ``/clock`` and set
            the node's ``use_sim_time``.
        thread_priority: ``SCHED_FIFO`` priority of the node's threads (the executor's and the
            state publisher's), 1 to 99; 0: ordinary. Below a real-time control loop's, so
            that a node thread holding the interpreter is not preempted by other processes
            while the loop waits for it (a refusal, without root or CAP_SYS_NICE, is ignored).

    Raises:
        rclpy's errors: invalid names or ROS arguments.
    """

    def __init__(self, loop: Any, *, node_name: str = DEFAULT_NODE_NAME, namespace: str = "",
                 ros_args: Sequence[str] = (), sim_time: bool = False,
                 thread_priority: int = 0) -> None:
        self.context = Context()
        rclpy.init(args=["go2-wbc", "--ros-args", *ros_args], context=self.context)
        overrides = [Parameter("use_sim_time", Parameter.Type.BOOL, True)] if sim_time else []
        try:
            self.node = Node(node_name, namespace=namespace, context=self.context,
                             parameter_overrides=overrides)
            self.servers = [RosActionServer(self.node, loop.runner, local, ros_name,
                                            ros_action_type(local))
                            for local, ros_name in ROS_ACTION_NAMES.items()]
            self.state = StatePublisher(self.node, sim_time=sim_time,
                                        on_start=partial(promote_thread, thread_priority))
            self.cmd_vel = CmdVelSubscriber(self.node, loop)
        except BaseException:
            rclpy.try_shutdown(context=self.context)
            raise
        loop.hooks.append(self.state.tick_hook)
        self._loop = loop
        self.executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS,
                                              context=self.context)
        # rclpy's pool of workers, which run the callbacks, replaced: promoted as they start.
        self.executor._executor = ThreadPoolExecutor(
            EXECUTOR_THREADS, initializer=partial(promote_thread, thread_priority))
        self.executor.add_node(self.node)
        self._priority = thread_priority
        self._thread = threading.Thread(target=self._spin, name="ros2-executor", daemon=True)
        self._switch_interval: float | None = None

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
        """Spin the executor in its own thread (the interpreter's switch interval set to
        :data:`SWITCH_INTERVAL_S` until :meth:`close`)."""
        self._switch_interval = sys.getswitchinterval()
        sys.setswitchinterval(SWITCH_INTERVAL_S)
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
        self.cmd_vel.destroy()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)
        if self._switch_interval is not None:
            sys.setswitchinterval(self._switch_interval)

    def _spin(self) -> None:
        promote_thread(self._priority)
        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass


def promote_thread(priority: int) -> None:
    """Run the calling thread under ``SCHED_FIFO`` at ``priority`` (0: leave it); a refusal
    (no root or CAP_SYS_NICE, no SCHED_FIFO) leaves it as it was."""
    if priority <= 0 or not hasattr(os, "sched_setscheduler"):
        return
    try:
        os.sched_setscheduler(threading.get_native_id(), os.SCHED_FIFO,
                              os.sched_param(priority))
    except OSError:
        pass
