"""The ROS 2 tutorial action clients, written as the tutorials write them, on a simulated GO2.

The two client classes below are the GO2 HighFive tutorial's callback client and the one-joint
FollowJointTrajectory client, as ROS 2 tutorials write them: messages filled field by field,
``Duration(...).to_msg()``, ``wait_for_server()``, ``send_goal_async`` with a feedback
callback, a goal-response callback, ``get_result_async`` with a result callback, and
``rclpy.shutdown()`` in the result callback. Only the imports differ from ROS 2, and the
small ``Node``/``rclpy`` stand-ins at the top play the part of rclpy's node and executor:
the node is a simulated GO2's control loop, and spinning runs its 1 kHz control ticks (in
simulated time) until ``rclpy.shutdown()``.
"""

from __future__ import annotations

from concurrent.futures import Future
from typing import Any

import numpy as np
import pytest

# The imports that replace ROS 2's:
#   from rclpy.action import ActionClient               -> from actions import ActionClient
#   from action_msgs.msg import GoalStatus              -> from actions import GoalStatus
#   from go2_interfaces.action import HighFive          -> HIGH_FIVE as HighFive
#   from control_msgs.action import FollowJointTrajectory
#                                                       -> FOLLOW_JOINT_TRAJECTORY as ...
#   from trajectory_msgs.msg import JointTrajectoryPoint -> from actions import ...
#   from rclpy.duration import Duration                 -> from actions.duration import ...
from actions import FOLLOW_JOINT_TRAJECTORY as FollowJointTrajectory
from actions import HIGH_FIVE as HighFive
from actions import ActionClient, GoalStatus, JointTrajectoryPoint
from actions.duration import Duration
from actions.go2.follow_joint_trajectory_behaviour import DEFAULT_GOAL_TOLERANCE_RAD
from sim.control_loop import ControlLoop
from wbc.model.description import JOINT_NAMES

#: Longest spin [s of simulated time] before the stand-in gives up.
SPIN_LIMIT_S = 30.0


# --- stand-ins for rclpy's node and executor ----------------------------------------------


class _Logger:
    def __init__(self, lines: list[str]) -> None:
        self.lines = lines

    def info(self, text: str) -> None:
        self.lines.append(text)


class Node:
    """rclpy.node.Node's part: a simulated GO2 (its control loop holds the action runner)."""

    def __init__(self, node_name: str) -> None:
        self.node_name = node_name
        self.loop = ControlLoop.simulated()
        self.runner = self.loop.runner  # what ActionClient(self, ...) uses
        self.log: list[str] = []

    def get_logger(self) -> _Logger:
        return _Logger(self.log)


class _Rclpy:
    """rclpy's init/spin/shutdown for one node: spinning runs control ticks until shutdown."""

    def __init__(self) -> None:
        self.running = False

    def init(self, args: Any = None) -> None:
        self.running = True

    def spin(self, node: Node) -> None:
        while self.running and node.loop.robot.time_s < SPIN_LIMIT_S:
            node.loop.spin_once()

    def shutdown(self) -> None:
        self.running = False


rclpy = _Rclpy()


# --- the GO2 HighFive tutorial's client -----------------------------------------------------


class HighFiveActionClient(Node):
    def __init__(self):
        super().__init__("high_five_action_client")
        self._action_client = ActionClient(self, HighFive, "high_five")

    def send_goal(self, target_height, hold_seconds):
        goal_msg = HighFive.Goal()
        goal_msg.target_height = target_height
        goal_msg.hold_seconds = hold_seconds

        self._action_client.wait_for_server()

        self._send_goal_future = self._action_client.send_goal_async(
            goal_msg, feedback_callback=self.feedback_callback)

        self._send_goal_future.add_done_callback(self.goal_response_callback)

    def goal_response_callback(self, future):
        goal_handle = future.result()
        if not goal_handle.accepted:
            self.get_logger().info("Goal rejected :(")
            return

        self.get_logger().info("Goal accepted :)")

        self._get_result_future = goal_handle.get_result_async()
        self._get_result_future.add_done_callback(self.get_result_callback)

    def get_result_callback(self, future):
        result = future.result().result
        status = future.result().status
        if status == GoalStatus.STATUS_SUCCEEDED:
            self.get_logger().info(f"Goal succeeded! Result: {result.message}")
        else:
            self.get_logger().info(f"Goal failed with status: {status}")
        rclpy.shutdown()

    def feedback_callback(self, feedback_msg):
        feedback = feedback_msg.feedback
        self.get_logger().info(f"Received feedback: {feedback.phase} {feedback.progress:.2f}")


def high_five_main(args=None):
    rclpy.init(args=args)

    action_client = HighFiveActionClient()

    action_client.send_goal(0.30, 0)

    rclpy.spin(action_client)
    return action_client


# --- the one-joint FollowJointTrajectory tutorial's client -----------------------------------


class FollowJointTrajectoryClient(Node):
    def __init__(self):
        super().__init__("follow_joint_trajectory_client")
        self._action_client = ActionClient(
            self, FollowJointTrajectory, "follow_joint_trajectory")

    def send_goal(self, angle):
        goal_msg = FollowJointTrajectory.Goal()
        goal_msg.trajectory.joint_names = ["FR_calf_joint"]

        point = JointTrajectoryPoint()
        point.positions = [angle]
        point.time_from_start = Duration(seconds=1, nanoseconds=0).to_msg()

        goal_msg.trajectory.points.append(point)

        self._action_client.wait_for_server()

        self._send_goal_future = self._action_client.send_goal_async(
            goal_msg, feedback_callback=self.feedback_callback)

        self._send_goal_future.add_done_callback(self.goal_response_callback)

    def goal_response_callback(self, future):
        goal_handle = future.result()
        if not goal_handle.accepted:
            self.get_logger().info("Goal rejected :(")
            return

        self.get_logger().info("Goal accepted :)")

        self._get_result_future = goal_handle.get_result_async()
        self._get_result_future.add_done_callback(self.get_result_callback)

    def get_result_callback(self, future):
        result = future.result().result
        self.get_logger().info(f"Result: {result.error_code} {result.error_string!r}")
        rclpy.shutdown()

    def feedback_callback(self, feedback_msg):
        feedback = feedback_msg.feedback
        reached = Duration.from_msg(feedback.desired.time_from_start).nanoseconds / 1e9
        self.get_logger().info(f"Received feedback: {reached} {feedback.error.positions}")


def follow_joint_trajectory_main(args=None):
    rclpy.init(args=args)

    action_client = FollowJointTrajectoryClient()

    action_client.send_goal(-1.9)

    rclpy.spin(action_client)
    return action_client


# --- the tests ------------------------------------------------------------------------------


def result_of(future: Future[Any]) -> Any:
    assert future.done(), "no result: the spin stand-in gave up"
    return future.result()


def test_the_high_five_tutorial_client_runs_to_succeeded() -> None:
    client = high_five_main()
    wrapped = result_of(client._get_result_future)
    assert wrapped.status == GoalStatus.SUCCEEDED
    assert client.log[0] == "Goal accepted :)"
    assert client.log[-1] == (
        "Goal succeeded! Result: high five done: foot raised to 0.300 m, held 0 s, back on "
        "four feet")
    feedback = [line.split()[2:] for line in client.log[1:-1]]
    phases = list(dict.fromkeys(phase for phase, _ in feedback))
    assert phases == ["shifting", "unloading", "raising", "ready", "lowering", "reloading",
                      "shifting_back", "complete"]
    progress = [float(value) for _, value in feedback]
    assert progress[-1] == 1.0 and progress == sorted(progress)
    assert not rclpy.running  # shut down by the result callback, not by the spin limit


def test_the_one_joint_follow_joint_trajectory_client_runs_to_succeeded() -> None:
    client = follow_joint_trajectory_main()
    wrapped = result_of(client._get_result_future)
    assert wrapped.status == GoalStatus.SUCCEEDED
    assert client.log[0] == "Goal accepted :)"
    assert client.log[-1] == (
        "Result: 0 'goal reached: the FR leg holds the last point, in swing: the FR foot stays "
        "up and the robot stands on three feet; a Stand goal puts the foot down'")
    # The trajectory time reached: 0 while the leg is released, then up to 1 s and past it.
    reached = [float(line.split()[2]) for line in client.log[1:-1]]
    assert reached[0] == 0.0 and reached == sorted(reached) and reached[-1] > 1.0
    calf = client.loop.true_state()[0][7 + JOINT_NAMES.index("FR_calf_joint")]
    assert calf == pytest.approx(-1.9, abs=DEFAULT_GOAL_TOLERANCE_RAD)
    sent = client._send_goal_future.result().goal  # the server's copy, as filled
    assert sent.trajectory.points[0].time_from_start.sec == 1
    assert np.isclose(sent.trajectory.points[0].positions[0], -1.9)
    assert not rclpy.running
