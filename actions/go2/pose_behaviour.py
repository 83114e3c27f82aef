"""Stand and Sit: move the whole body to the standing or the lying pose on four feet."""

from __future__ import annotations

import math
from typing import Any

from actions.behaviour import Behaviour, StepResult
from actions.feedback_throttle import FeedbackThrottle
from actions.go2.go2_interfaces import PoseGoal
from actions.go2.robot_context import RobotContext
from actions.responses import GoalResponse, Rejection
from wbc.motions.posture_transition import PostureTransition, TransitionPhase

#: Rejection code of a Stand or Sit goal with an invalid duration.
INVALID_DURATION = 20
#: Durations [s] a Stand or Sit goal may ask for.
MIN_DURATION_S, MAX_DURATION_S = 0.5, 10.0


def validate_pose_goal(context: RobotContext, goal: PoseGoal) -> GoalResponse | Rejection:
    """The goal callback of Stand and Sit: ACCEPT, or a coded rejection naming the range.

    Args:
        context: The robot's context, which every GO2 goal callback takes; unused, since a
            Stand or a Sit may start from any pose.
        goal: The goal.
    """
    duration = goal.duration_s
    if not isinstance(duration, (int, float)) or not math.isfinite(duration) or not (
            MIN_DURATION_S <= duration <= MAX_DURATION_S):
        return Rejection(INVALID_DURATION, (
            f"duration_s: expected a duration in [{MIN_DURATION_S:g}, {MAX_DURATION_S:g}] s, "
            f"received {duration!r}"))
    return GoalResponse.ACCEPT


class PoseBehaviour(Behaviour[PoseGoal, Any, Any]):
    """Runs a :class:`PostureTransition` to ``pose``; a cancel freezes the motion where it is.

    Args:
        context: The robot's shared context.
        pose: ``"standing"`` (Stand) or ``"lying"`` (Sit).
        result_type, feedback_type: The action's message types.
        phase_name: Feedback phase while moving (``"rising"``, ``"sitting"``).
    """

    def __init__(self, context: RobotContext, pose: str, result_type: type, feedback_type: type,
                 phase_name: str):
        self.context = context
        self.pose = pose
        self.result_type = result_type
        self.feedback_type = feedback_type
        self.phase_name = phase_name
        self._transition: PostureTransition | None = None
        self._cancel_reason = ""
        self._throttle = FeedbackThrottle()

    def start(self, goal: PoseGoal, now_s: float) -> None:
        self._transition = PostureTransition(self.context.controller, self.pose,
                                             duration_s=goal.duration_s)
        self._transition.start(now_s)

    def step(self, now_s: float) -> StepResult[Any, Any]:
        transition = self._transition
        if self.context.fault:
            transition.stop()
            return StepResult.aborted(self.result_type(success=False, message=(
                f"aborted: controller fault ({self.context.fault})")),
                self._feedback(now_s, "aborted", transition.progress))
        phase = transition.advance(now_s)
        if phase is not TransitionPhase.DONE:
            name = "placing_foot" if phase is TransitionPhase.PLACING_FOOT else self.phase_name
            return StepResult.running(self._feedback(now_s, name, transition.progress))
        if self._cancel_reason:
            return StepResult.canceled(self.result_type(success=False, message=(
                f"canceled ({self._cancel_reason}): stopped on four feet")),
                self._feedback(now_s, "canceled", transition.progress))
        return StepResult.succeeded(self.result_type(success=True, message=(
            f"reached the {self.pose} pose")), self._feedback(now_s, "complete", 1.0))

    def cancel(self, now_s: float, reason: str) -> None:
        self._cancel_reason = reason
        if self._transition is not None:
            self._transition.stop()

    def abort_result(self, message: str) -> Any:
        return self.result_type(success=False, message=message)

    def _feedback(self, now_s: float, phase: str, progress: float) -> Any:
        if not self._throttle.due(now_s, phase):
            return None
        return self.feedback_type(phase=phase, progress=float(progress))
