"""The high five's action client as the ROS 2 tutorial "Writing an action server and client
(Python)" writes it (a Node subclass, ActionClient, wait_for_server, send_goal_async with a
feedback callback, add_done_callback on the goal and result futures, rclpy.spin), with two
additions for the tests: it prints one JSON line per event, and ``--cancel-after S`` cancels
the goal S seconds (of the node's clock) after it was accepted.

Run: ``python tutorial_high_five_client.py [--cancel-after S] [--height M] [--hold S]
[--ros-args ...]``.
"""

import argparse
import json
import sys

import rclpy
from go2_interfaces.action import HighFive
from rclpy.action import ActionClient
from rclpy.node import Node


def emit(**event):
    print(json.dumps(event), flush=True)


class HighFiveActionClient(Node):

    def __init__(self, action_name, cancel_after):
        super().__init__('high_five_action_client')
        self._action_client = ActionClient(self, HighFive, action_name)
        self._cancel_after = cancel_after
        self._goal_handle = None
        self._cancel_timer = None

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
            self.get_logger().info('Goal rejected :(')
            emit(event='rejected')
            rclpy.shutdown()
            return

        self.get_logger().info('Goal accepted :)')
        emit(event='accepted', t=self.get_clock().now().nanoseconds * 1e-9)
        self._goal_handle = goal_handle

        self._get_result_future = goal_handle.get_result_async()
        self._get_result_future.add_done_callback(self.get_result_callback)
        if self._cancel_after is not None:
            self._cancel_timer = self.create_timer(self._cancel_after, self.cancel_goal)

    def cancel_goal(self):
        self._cancel_timer.cancel()
        emit(event='cancel', t=self.get_clock().now().nanoseconds * 1e-9)
        future = self._goal_handle.cancel_goal_async()
        future.add_done_callback(self.cancel_done_callback)

    def cancel_done_callback(self, future):
        emit(event='cancel_response', goals_canceling=len(future.result().goals_canceling))

    def get_result_callback(self, future):
        result = future.result().result
        status = future.result().status
        self.get_logger().info('Result: {0}'.format(result.message))  # noqa: UP030, UP032 (as the tutorial)
        emit(event='result', status=status, success=result.success, message=result.message,
             t=self.get_clock().now().nanoseconds * 1e-9)
        rclpy.shutdown()

    def feedback_callback(self, feedback_msg):
        feedback = feedback_msg.feedback
        emit(event='feedback', phase=feedback.phase, progress=feedback.progress)


def main(args=None):
    parser = argparse.ArgumentParser()
    parser.add_argument('--action', default='high_five')
    parser.add_argument('--height', type=float, default=0.4)
    parser.add_argument('--hold', type=int, default=2)
    parser.add_argument('--cancel-after', type=float)
    ours = parser.parse_args(rclpy.utilities.remove_ros_args(sys.argv)[1:])

    rclpy.init(args=args)

    action_client = HighFiveActionClient(ours.action, ours.cancel_after)

    action_client.send_goal(ours.height, ours.hold)

    try:
        rclpy.spin(action_client)
    except rclpy.executors.ExternalShutdownException:
        pass


if __name__ == '__main__':
    main()
