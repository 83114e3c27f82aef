"""One of the runner's action servers served to ROS 2 as an rclpy ``ActionServer``.

The runner decides everything, as for a local or DDS client: rclpy's callbacks, on the
executor's threads (never on the control loop's), hand the goal and cancel requests to it
through its thread-safe entry points (``submit_goal``, ``submit_cancel``, via an
:class:`~actions.action_client.ActionClient`) and wait for the tick that answers them. The
runner's feedback and result callbacks (on the ticking thread) only queue what they get; the
goal's execute callback, on an executor thread, converts and publishes it. So the goal is
accepted or rejected for the runner's reasons (logged: ROS 2's goal response carries no
reason), its phases and progress are the behaviour's, a cancel is the behaviour's unwind, and
the goal ends with exactly the runner's one result.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeoutError
from dataclasses import dataclass, field
from typing import Any

from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node

from actions.action_client import ActionClient
from actions.client_goal_handle import ClientGoalHandle
from actions.goal_status import GoalStatus
from actions.responses import CancelReturnCode, FeedbackMessage
from go2_ros2.message_conversion import to_library, to_ros
from wbc.core.errors import WbcError

logger = logging.getLogger(__name__)

#: Longest wait [s] for the control loop to answer a goal or cancel request (it answers on
#: its next tick: 1 or 2 ms; longer only while the loop waits for the robot's state).
ANSWER_WAIT_S = 5.0
#: How often [s] a running goal's execute callback looks for feedback when none came.
FEEDBACK_POLL_S = 0.1
#: Pause [s] between the last feedback and the result: ROS 2 orders no topic against a
#: service reply, and a tutorial client stops at its result, so the last feedback (the
#: "complete" phase) is given a head start.
LAST_FEEDBACK_LEAD_S = 0.05


@dataclass(eq=False)
class _Goal:
    """A goal accepted by the runner, between its acceptance and its result."""

    handle: ClientGoalHandle
    events: queue.SimpleQueue[Any] = field(default_factory=queue.SimpleQueue)


class _ResultReady:
    """Queued after the last feedback: the runner's result is there."""


class RosActionServer:
    """Serves the runner's action ``local_name`` as the ROS 2 action ``ros_name``.

    Args:
        node: The rclpy node.
        runner: The control loop's action runner.
        local_name: The runner's name of the action (``high_five``).
        ros_name: The ROS 2 action name (``high_five``, or
            ``/joint_trajectory_controller/follow_joint_trajectory``); relative names take
            the node's namespace, and ``--ros-args --remap`` applies.
        ros_type: The rosidl action type (``go2_interfaces.action.HighFive``).
    """

    def __init__(self, node: Node, runner: Any, local_name: str, ros_name: str,
                 ros_type: Any) -> None:
        self.local_name = local_name
        self.ros_type = ros_type
        self._client = ActionClient(runner, local_name)
        self._action_type = self._client.action_type
        # Accepted by the runner, by id() of rclpy's goal message until rclpy hands over the
        # goal's handle, then by the goal's UUID until its result.
        self._accepted: dict[int, tuple[Any, _Goal]] = {}
        self._goals: dict[bytes, _Goal] = {}
        self._lock = threading.Lock()
        self._logger = node.get_logger()
        self.server = ActionServer(
            node, ros_type, ros_name, execute_callback=self._execute,
            goal_callback=self._on_goal, handle_accepted_callback=self._on_accepted,
            cancel_callback=self._on_cancel, callback_group=ReentrantCallbackGroup())

    def destroy(self) -> None:
        """Destroy the rclpy server."""
        self.server.destroy()

    # -- rclpy's callbacks, on executor threads ---------------------------------------------

    def _on_goal(self, ros_goal: Any) -> GoalResponse:
        try:
            goal = to_library(ros_goal, self._action_type.goal_type)
        except WbcError as err:
            self._logger.warning(f"goal for '{self.local_name}' rejected: {err}")
            return GoalResponse.REJECT
        accepted = _Goal(handle=None)  # type: ignore[arg-type]  # set below
        future = self._client.send_goal_async(goal, accepted.events.put)
        try:
            handle = future.result(timeout=ANSWER_WAIT_S)
        except FutureTimeoutError:
            future.add_done_callback(_cancel_if_accepted)
            self._logger.warning(
                f"goal for '{self.local_name}' rejected: the control loop did not answer "
                f"within {ANSWER_WAIT_S:g} s")
            return GoalResponse.REJECT
        if not handle.accepted:
            rejection = handle.rejection
            self._logger.warning(f"goal {handle.goal_id} for '{self.local_name}' rejected "
                                 f"(code {rejection.code}): {rejection.message}")
            return GoalResponse.REJECT
        accepted.handle = handle
        handle.get_result_async().add_done_callback(
            lambda _: accepted.events.put(_ResultReady()))
        with self._lock:  # rclpy hands the same goal message to _on_accepted
            self._accepted[id(ros_goal)] = (ros_goal, accepted)
        self._logger.info(f"goal {handle.goal_id} for '{self.local_name}' accepted")
        return GoalResponse.ACCEPT

    def _on_accepted(self, goal_handle: Any) -> None:
        with self._lock:
            _, accepted = self._accepted.pop(id(goal_handle.request))
            self._goals[bytes(goal_handle.goal_id.uuid)] = accepted
        goal_handle.execute()

    def _on_cancel(self, goal_handle: Any) -> CancelResponse:
        accepted = self._goal_of(goal_handle)
        try:
            response = accepted.handle.cancel_goal_async().result(timeout=ANSWER_WAIT_S)
        except FutureTimeoutError:
            self._logger.warning(f"cancel of goal {accepted.handle.goal_id} refused: the "
                                 f"control loop did not answer within {ANSWER_WAIT_S:g} s")
            return CancelResponse.REJECT
        if response.return_code != CancelReturnCode.ERROR_NONE:
            self._logger.warning(f"cancel of goal {accepted.handle.goal_id} refused: "
                                 f"{response.message}")
            return CancelResponse.REJECT
        self._logger.info(f"cancel of goal {accepted.handle.goal_id} accepted")
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle: Any) -> Any:
        accepted = self._goal_of(goal_handle)
        feedback_type = self.ros_type.Feedback
        published = False
        while True:
            try:
                event = accepted.events.get(timeout=FEEDBACK_POLL_S)
            except queue.Empty:
                continue
            if isinstance(event, _ResultReady):
                break
            message: FeedbackMessage = event
            goal_handle.publish_feedback(to_ros(message.feedback, feedback_type))
            published = True
        if published:
            time.sleep(LAST_FEEDBACK_LEAD_S)
        wrapped = accepted.handle.get_result_async().result()
        status = wrapped.status
        if status == GoalStatus.SUCCEEDED:
            goal_handle.succeed()
        elif status == GoalStatus.CANCELED and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:  # ABORTED, or canceled by the runner itself (not a ROS 2 request)
            goal_handle.abort()
        self._logger.info(f"goal {accepted.handle.goal_id} for '{self.local_name}' "
                          f"{status.name}: {_message_of(wrapped.result)}")
        with self._lock:
            self._goals.pop(bytes(goal_handle.goal_id.uuid), None)
        return to_ros(wrapped.result, self.ros_type.Result)

    def _goal_of(self, goal_handle: Any) -> _Goal:
        with self._lock:
            accepted = self._goals.get(bytes(goal_handle.goal_id.uuid))
            if accepted is None:  # a cancel before rclpy handed the goal over
                accepted = self._accepted[id(goal_handle.request)][1]
        return accepted


def _message_of(result: Any) -> str:
    return str(getattr(result, "message", getattr(result, "error_string", "")))


def _cancel_if_accepted(future: Future[ClientGoalHandle]) -> None:
    """A goal the runner accepted after its client stopped waiting: cancel it."""
    handle = future.result()
    if handle.accepted:
        handle.cancel_goal_async()
