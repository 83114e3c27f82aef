"""A high five through the public API, written like the ROS 2 action client tutorial.

Run it with ``.venv/bin/python scripts/high_five.py``; ``go2-wbc high-five`` does the same
with more options. The simulated robot's control loop plays the part of the ROS 2 node:
spinning it runs one 1 kHz control tick, which also delivers the callbacks.
"""

from __future__ import annotations

import sys

from actions import GoalStatus, HighFiveGoal
from sim.control_loop import ControlLoop


class HighFiveActionClient:
    """Sends one HighFive goal and prints its acceptance, feedback and result."""

    def __init__(self, loop: ControlLoop):
        self.loop = loop
        self._action_client = loop.client("high_five")  # rclpy: ActionClient(node, ...)
        self._last_phase = ""
        self.status: GoalStatus | None = None  # set when the goal has ended

    def send_goal(self, target_height: float, hold_seconds: int) -> None:
        goal_msg = HighFiveGoal(target_height=target_height, hold_seconds=hold_seconds)
        print(f"Sending goal: foot to {target_height} m, hold {hold_seconds} s")
        send_goal_future = self._action_client.send_goal_async(
            goal_msg, feedback_callback=self.feedback_callback)
        send_goal_future.add_done_callback(self.goal_response_callback)

    def goal_response_callback(self, future) -> None:
        goal_handle = future.result()
        if not goal_handle.accepted:
            print(f"Goal rejected: {goal_handle.rejection.message}")
            self.status = GoalStatus.UNKNOWN
            return
        print("Goal accepted")
        goal_handle.get_result_async().add_done_callback(self.get_result_callback)

    def feedback_callback(self, feedback_msg) -> None:
        feedback = feedback_msg.feedback
        if feedback.phase != self._last_phase:  # it comes at 50 Hz: print the phase changes
            self._last_phase = feedback.phase
            print(f"Feedback: {feedback.phase} ({feedback.progress:.0%}) "
                  f"at {self.loop.robot.time_s:.2f} s")

    def get_result_callback(self, future) -> None:
        wrapped = future.result()
        print(f"Result: {wrapped.status.name}: {wrapped.result.message}")
        self.status = wrapped.status


def main() -> int:
    loop = ControlLoop.simulated()
    action_client = HighFiveActionClient(loop)
    action_client.send_goal(target_height=0.40, hold_seconds=2)
    while action_client.status is None:  # rclpy.spin(node), until the goal has ended
        loop.spin_once()
    return 0 if action_client.status == GoalStatus.SUCCEEDED else 1


if __name__ == "__main__":
    sys.exit(main())
