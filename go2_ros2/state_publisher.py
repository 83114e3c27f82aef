"""Publishes what ROS 2 tools expect of a robot: ``/joint_states``, ``/imu``, ``/odom`` and, for
the simulated robot, ``/clock``.

The control loop's hook (:meth:`StatePublisher.tick_hook`, on the ticking thread) only keeps a
copy of the tick's estimate every :data:`PUBLISH_PERIOD_S` of robot time and sets an event;
the messages are built and published by the publisher's own thread (rcl's publishers are
thread-safe), not by the executor, whose wait sets (four action servers' worth) cost more than
a publication. So the 1 kHz tick pays a few array copies a publication, and rclpy never runs
inside it. The messages are built once and refilled (arrays of ``float64`` by ``array``, which
the generated setters take without a per-element check).
"""

from __future__ import annotations

import array
import math
import threading
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from builtin_interfaces.msg import Time as TimeMsg
from nav_msgs.msg import Odometry
from rclpy.node import Node
from rclpy.qos import QoSProfile, qos_profile_sensor_data
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState

from wbc.model.orders import DESCRIPTION_ORDERS

#: Robot time [s] between two publications (250 Hz: >= 100 Hz at 500 Hz and 1 kHz control).
PUBLISH_PERIOD_S = 0.004
#: The odometry's frames (REP 105) and the IMU's (the GO2's URDF base link carries it).
ODOM_FRAME, BASE_FRAME, IMU_FRAME = "odom", "base", "imu"


class Snapshot(NamedTuple):
    """One tick's estimate, copied on the ticking thread.

    Attributes:
        time_s: The robot's time [s].
        q: Configuration (19,): base position [m], quaternion (x, y, z, w), 12 joints [rad].
        v: Velocity (18,): base linear [m/s] and angular [rad/s] velocity in the base frame,
            12 joint velocities [rad/s].
        tau: The commanded joint torques (12,) [N m].
    """

    time_s: float
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray


def time_msg(seconds: float) -> TimeMsg:
    """``builtin_interfaces/Time`` of a time in seconds."""
    sec = math.floor(seconds)
    return TimeMsg(sec=int(sec), nanosec=min(round((seconds - sec) * 1e9), 999_999_999))


class StatePublisher:
    """The robot's state topics of a node.

    Args:
        node: The rclpy node (topic names relative: the namespace and remaps apply).
        sim_time: Stamp with the robot's time and publish it on ``/clock`` (the simulated
            robot); otherwise stamp with the node's clock.
        on_start: Called first in the publisher's thread (its scheduling).
    """

    def __init__(self, node: Node, *, sim_time: bool,
                 on_start: Callable[[], None] | None = None) -> None:
        self.node = node
        self.sim_time = sim_time
        self.joint_names = list(DESCRIPTION_ORDERS.joint_names)
        self.published = 0
        self._latest: Snapshot | None = None
        self._next_s = -math.inf
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._stop = False
        sensor = qos_profile_sensor_data
        self._joint_states = node.create_publisher(JointState, "joint_states", 10)
        self._imu = node.create_publisher(Imu, "imu", sensor)
        self._odom = node.create_publisher(Odometry, "odom", 10)
        self._clock = (node.create_publisher(Clock, "/clock", QoSProfile(depth=1))
                       if sim_time else None)
        #: The topics published (relative names, as created).
        self.topics = ["joint_states", "imu", "odom"] + (["/clock"] if sim_time else [])
        self._joints_msg = JointState()
        self._joints_msg.name = self.joint_names
        self._imu_msg = Imu()
        self._imu_msg.header.frame_id = IMU_FRAME
        # The estimate holds no specific force: marked unknown, as REP 145 says.
        self._imu_msg.linear_acceleration_covariance[0] = -1.0
        self._odom_msg = Odometry()
        self._odom_msg.header.frame_id = ODOM_FRAME
        self._odom_msg.child_frame_id = BASE_FRAME
        self._on_start = on_start
        self._thread = threading.Thread(target=self._run, name="ros2-state", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop the publisher's thread."""
        self._stop = True
        self._wake.set()
        self._thread.join(timeout=2.0)

    def tick_hook(self, loop: Any, output: Any) -> None:
        """A control loop tick hook: keep this tick's estimate every :data:`PUBLISH_PERIOD_S`
        and wake the publisher."""
        now = loop.context.now_s
        if now < self._next_s:
            return
        self._next_s = now + PUBLISH_PERIOD_S - 1e-9
        snapshot = Snapshot(now, loop.context.q.copy(), loop.context.v.copy(),
                            np.array(output.tau, dtype=float))
        with self._lock:
            self._latest = snapshot
        self._wake.set()

    def _run(self) -> None:
        if self._on_start is not None:
            self._on_start()
        while True:
            self._wake.wait()
            self._wake.clear()
            if self._stop:
                return
            try:
                self._publish()
            except Exception as err:  # noqa: BLE001 (logged; the thread must go on)
                if self._stop:
                    return
                self.node.get_logger().error(f"state topics: {err}")

    def _publish(self) -> None:
        with self._lock:
            snap, self._latest = self._latest, None
        if snap is None:
            return
        stamp = (time_msg(snap.time_s) if self.sim_time
                 else self.node.get_clock().now().to_msg())
        if self._clock is not None:
            self._clock.publish(Clock(clock=stamp))
        q, v = snap.q, snap.v
        joints = self._joints_msg
        joints.header.stamp = stamp
        joints.position = array.array("d", q[7:])
        joints.velocity = array.array("d", v[6:])
        joints.effort = array.array("d", snap.tau)
        self._joint_states.publish(joints)
        imu = self._imu_msg
        imu.header.stamp = stamp
        _set_quaternion(imu.orientation, q[3:7])
        _set_vector(imu.angular_velocity, v[3:6])
        self._imu.publish(imu)
        odom = self._odom_msg
        odom.header.stamp = stamp
        _set_vector(odom.pose.pose.position, q[0:3])
        _set_quaternion(odom.pose.pose.orientation, q[3:7])
        _set_vector(odom.twist.twist.linear, v[0:3])
        _set_vector(odom.twist.twist.angular, v[3:6])
        self._odom.publish(odom)
        self.published += 1


def _set_quaternion(message: Any, xyzw: np.ndarray) -> None:
    message.x, message.y, message.z, message.w = (float(x) for x in xyzw)


def _set_vector(message: Any, xyz: np.ndarray) -> None:
    message.x, message.y, message.z = (float(x) for x in xyz)
