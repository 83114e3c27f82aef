"""``go2-wbc send-goal ... --ros2``: ``ros2 action send_goal`` for users without ros2cli, said
as ``go2-wbc send-goal`` says a goal to the simulated GO2 (feedback times in wall-clock seconds
since the goal was sent). The command line (:mod:`sim.cli.ros2_command`) gives the printing
and turns the outcome into its exit status.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from enum import Enum
from typing import Any

import rclpy
from action_msgs.msg import GoalStatus as RosGoalStatus
from rclpy.action import ActionClient
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

from actions.go2.go2_actions import GO2_ACTIONS
from actions.goal_status import GoalStatus
from actions.messages import Message
from go2_ros2.message_conversion import to_library, to_ros
from go2_ros2.ros_names import ROS_ACTION_NAMES, ros_action_type

#: Longest wait [s] for the action server, and for the goal's acceptance.
SERVER_WAIT_S = 10.0
#: Longest wait [s] for a canceled goal's result (its unwind).
CANCEL_WAIT_S = 15.0
#: How long [s] feedback is still taken after the result arrived.
FEEDBACK_DRAIN_S = 0.3


class Outcome(Enum):
    """How a goal sent with :func:`send_goal_over_ros2` ended."""

    SUCCEEDED = "succeeded"
    NOT_SUCCEEDED = "canceled, aborted or no result in time"
    REJECTED = "rejected"
    UNAVAILABLE = "no action server, or no answer"
    INTERRUPTED = "interrupted (Ctrl-C): canceled"


def send_goal_over_ros2(action_name: str, goal: Message, *, say: Callable[[str], None],
                        block: Callable[[Message], str],
                        feedback_line: Callable[[Message], str] | None,
                        timeout_s: float | None = None, namespace: str = "",
                        ros_args: Sequence[str] = ()) -> Outcome:
    """Send ``goal`` (the library's message, validated) to the ROS 2 action of the runner's
    ``action_name``, say its progress and result as ``ros2 action send_goal`` does.

    Args:
        action_name: The runner's name of the action (``high_five``).
        goal: The goal.
        say: Prints one or more lines.
        block: A message as an indented block (the goal, the result).
        feedback_line: A feedback message as one line; ``None``: no feedback printed.
        timeout_s: Wall-clock seconds before the goal is canceled (``None``: no limit).
        namespace: The node's namespace (the action is looked up under it).
        ros_args: ROS 2 arguments (``--remap high_five:=wave``).
    """
    action_type = GO2_ACTIONS[action_name]
    ros_type = ros_action_type(action_name)
    context = Context()
    rclpy.init(args=["go2-wbc", "--ros-args", *ros_args], context=context)
    node = Node("go2_wbc_send_goal", namespace=namespace, context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    client = ActionClient(node, ros_type, ROS_ACTION_NAMES[action_name])

    def spin_until(done: Callable[[], bool], timeout_s: float | None) -> bool:
        end = None if timeout_s is None else time.monotonic() + timeout_s
        while not done():
            if end is not None and time.monotonic() >= end:
                return False
            executor.spin_once(timeout_sec=0.05)
        return True

    try:
        resolved = node.resolve_topic_name(ROS_ACTION_NAMES[action_name])
        say(f"Waiting for an action server to become available ({resolved})...")
        if not client.wait_for_server(timeout_sec=SERVER_WAIT_S):
            print(f"go2-wbc: no action server {resolved} ({ros_type.__module__}."
                  f"{ros_type.__name__}) within {SERVER_WAIT_S:g} s: is 'go2-wbc ros2' (or "
                  f"'run --dds --ros2') running, on the same ROS_DOMAIN_ID?", file=sys.stderr)
            return Outcome.UNAVAILABLE
        say("Sending goal:\n" + block(goal) + "\n")
        sent_s = time.monotonic()

        def feedback(message: Any) -> None:
            if feedback_line is None:
                return
            text = feedback_line(to_library(message.feedback, action_type.feedback_type))
            say(f"Feedback [{time.monotonic() - sent_s:7.3f} s]: {text}")

        goal_future = client.send_goal_async(to_ros(goal, ros_type.Goal),
                                             feedback_callback=feedback)
        if not spin_until(goal_future.done, SERVER_WAIT_S):
            print(f"go2-wbc: the server did not answer within {SERVER_WAIT_S:g} s",
                  file=sys.stderr)
            return Outcome.UNAVAILABLE
        handle = goal_future.result()
        if not handle.accepted:
            say("Goal was rejected (the node's log says why).")
            return Outcome.REJECTED
        say(f"Goal accepted with ID: {bytes(handle.goal_id.uuid).hex()}\n")
        result_future = handle.get_result_async()
        interrupted = False
        try:
            finished = spin_until(result_future.done, timeout_s)
        except KeyboardInterrupt:
            say("Interrupted: canceling the goal")
            finished, interrupted = False, True
        if not finished:
            if not interrupted:
                say(f"No result after {timeout_s:g} s: canceling the goal")
            handle.cancel_goal_async()
            if not spin_until(result_future.done, CANCEL_WAIT_S):
                say(f"No result within {CANCEL_WAIT_S:g} s of the cancel")
                return Outcome.INTERRUPTED if interrupted else Outcome.NOT_SUCCEEDED
        # ROS 2 orders no topic against a service reply: the last feedback may come after
        # the result; a short wait prints it before the result, where it belongs.
        spin_until(lambda: False, FEEDBACK_DRAIN_S)
        response = result_future.result()
        result = to_library(response.result, action_type.result_type)
        say("\nResult:\n" + block(result) + "\n")
        status = GoalStatus(response.status)
        say(f"Goal finished with status: {status.name}")
        if interrupted:
            return Outcome.INTERRUPTED
        return (Outcome.SUCCEEDED if response.status == RosGoalStatus.STATUS_SUCCEEDED
                else Outcome.NOT_SUCCEEDED)
    finally:
        client.destroy()
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown(context=context)
