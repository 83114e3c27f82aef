"""A one-joint FollowJointTrajectory client as the ROS 2 courses write it (ActionClient on
'/joint_trajectory_controller/follow_joint_trajectory', goal_time_tolerance and
time_from_start from rclpy.duration.Duration(...).to_msg(), callbacks, rclpy.spin), moving
FR_calf_joint; it prints one JSON line per event for the tests.

Run: ``python tutorial_trajectory_client.py [POSITION_RAD [SECONDS]] [--ros-args ...]``.
"""

import json
import sys

import rclpy
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from rclpy.duration import Duration
from rclpy.node import Node
from trajectory_msgs.msg import JointTrajectoryPoint


def emit(**event):
    print(json.dumps(event), flush=True)


class TrajectoryActionClient(Node):

    def __init__(self):
        super().__init__('trajectory_action_client')
        self._action_client = ActionClient(
            self, FollowJointTrajectory, '/joint_trajectory_controller/follow_joint_trajectory')

    def send_goal(self, position, seconds):
        goal_msg = FollowJointTrajectory.Goal()
        goal_msg.trajectory.joint_names = ['FR_calf_joint']
        point = JointTrajectoryPoint()
        point.positions = [position]
        point.time_from_start = Duration(seconds=seconds).to_msg()
        goal_msg.trajectory.points.append(point)
        goal_msg.goal_time_tolerance = Duration(seconds=0.5).to_msg()

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
        emit(event='accepted')
        self._get_result_future = goal_handle.get_result_async()
        self._get_result_future.add_done_callback(self.get_result_callback)

    def get_result_callback(self, future):
        result = future.result().result
        emit(event='result', status=future.result().status, error_code=result.error_code,
             error_string=result.error_string)
        rclpy.shutdown()

    def feedback_callback(self, feedback_msg):
        feedback = feedback_msg.feedback
        emit(event='feedback', joint_names=list(feedback.joint_names),
             desired=list(feedback.desired.positions), actual=list(feedback.actual.positions),
             error=list(feedback.error.positions))


def main(args=None):
    ours = rclpy.utilities.remove_ros_args(sys.argv)[1:]
    position = float(ours[0]) if ours else -1.9
    seconds = float(ours[1]) if len(ours) > 1 else 1.0
    rclpy.init(args=args)
    action_client = TrajectoryActionClient()
    action_client.send_goal(position, seconds)
    try:
        rclpy.spin(action_client)
    except rclpy.executors.ExternalShutdownException:
        pass


if __name__ == '__main__':
    main()
