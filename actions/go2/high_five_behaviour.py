"""HighFive: raise the front-right foot to a height, hold it, put it back down."""

from __future__ import annotations

import math

from actions.behaviour import Behaviour, StepResult
from actions.feedback_throttle import FeedbackThrottle
from actions.go2.go2_interfaces import HighFiveFeedback, HighFiveGoal, HighFiveResult
from actions.go2.robot_context import RobotContext
from actions.responses import GoalResponse, Rejection
from wbc.core.errors import WbcError
from wbc.motions.leg_lift import MAX_HEIGHT_M, MIN_HEIGHT_M, LegLift, LiftPhase
from wbc.motions.posture_transition import PostureTransition, TransitionPhase

#: Longest hold [s] a goal may ask for.
MAX_HOLD_S = 60
#: Rejection codes of HighFive goals (beside the runner's own, 1 to 4).
INVALID_TARGET_HEIGHT, INVALID_HOLD_SECONDS, ROBOT_NOT_READY = 10, 11, 12

#: Feedback phase names, as the ROS course's HighFive server reports them.
PHASE_NAMES = {
    LiftPhase.SHIFTING: "shifting", LiftPhase.UNLOADING: "unloading",
    LiftPhase.RAISING: "raising", LiftPhase.HOLDING: "ready",
    LiftPhase.LOWERING: "lowering", LiftPhase.RELOADING: "reloading",
    LiftPhase.SHIFTING_BACK: "shifting_back", LiftPhase.DONE: "complete",
}
#: Consecutive damping fallbacks [ticks] after which the goal ends at once: the
#: controller cannot carry out an unwind any more.
FAULT_LIMIT_TICKS = 50
#: Share of the progress bar the stand-up takes when the robot is not standing.
_STAND_SHARE = 0.15
# The phases the tick tests, by plain name: a member looked up on its enum class costs about
# 0.1 us in Python 3.11 (several times that on a loaded machine).
_WATCHED = frozenset((LiftPhase.UNLOADING, LiftPhase.RAISING, LiftPhase.HOLDING))
_DONE, _STAND_DONE = LiftPhase.DONE, TransitionPhase.DONE


def validate_high_five_goal(context: RobotContext, goal: HighFiveGoal) -> GoalResponse | Rejection:
    """The goal callback: ACCEPT, or a coded rejection naming the field and the valid range."""
    height = goal.target_height
    if not isinstance(height, (int, float)) or not math.isfinite(height) or not (
            MIN_HEIGHT_M <= height <= MAX_HEIGHT_M):
        return Rejection(INVALID_TARGET_HEIGHT, (
            f"target_height: expected a height of the front-right foot above the ground in "
            f"[{MIN_HEIGHT_M:.2f}, {MAX_HEIGHT_M:.2f}] m, received {height!r}"))
    hold = goal.hold_seconds
    if isinstance(hold, bool) or not isinstance(hold, int) or not 0 <= hold <= MAX_HOLD_S:
        return Rejection(INVALID_HOLD_SECONDS, (
            f"hold_seconds: expected a whole number of seconds in [0, {MAX_HOLD_S}], "
            f"received {hold!r}"))
    if not context.is_upright():
        return Rejection(ROBOT_NOT_READY, (
            f"robot not able: base tilt {context.tilt_deg():.0f} deg, height {context.q[2]:.2f} m;"
            " it must be upright (send a Stand goal once it is)"))
    return GoalResponse.ACCEPT


class HighFiveBehaviour(Behaviour[HighFiveGoal, HighFiveResult, HighFiveFeedback]):
    """Stand first if needed; shift onto three legs; raise, hold, lower; back on four legs.

    Watches the balance while a foot is unloaded or raised: a tilt above 12 deg, or the
    capture point leaving the three feet's support polygon, puts the foot down fast and
    ends ABORTED. So does a
    controller fault (a fallback tick); a fault lasting ``FAULT_LIMIT_TICKS`` ends the goal
    ABORTED at once.
    """

    def __init__(self, context: RobotContext, *, leg: str = "FR"):
        self.context = context
        self.leg = leg
        self._stand: PostureTransition | None = None
        self._stood = False  # a stand-up took the first share of the progress
        self._lift: LegLift | None = None
        self._throttle = FeedbackThrottle()
        self._progress = 0.0
        self._cancel_reason = ""
        self._abort_reason = ""

    def start(self, goal: HighFiveGoal, now_s: float) -> None:
        self.goal = goal
        ctrl = self.context.controller
        # Validated again at start: the robot may have changed since acceptance.
        self._lift = LegLift(ctrl, leg=self.leg, height_m=goal.target_height,
                             hold_s=float(goal.hold_seconds))
        if not self.context.is_standing():
            self._stand = PostureTransition(ctrl, "standing", duration_s=1.5)
            self._stand.start(now_s)
            self._stood = True
        else:
            self._lift.start(now_s)

    def step(self, now_s: float) -> StepResult[HighFiveResult, HighFiveFeedback]:
        fault = self.context.fault
        if fault:
            if self.context.consecutive_fallbacks >= FAULT_LIMIT_TICKS:
                return StepResult.aborted(HighFiveResult(success=False, message=(
                    f"aborted: controller fault for {self.context.consecutive_fallbacks} ticks "
                    f"({fault}); the controller holds the joints with damping while the fault "
                    "lasts; a Stand goal puts a raised foot down afterwards")),
                    self._feedback(now_s, "aborted"))
            if not self._abort_reason:
                self._abort_reason = f"controller fault ({fault})"
                if self._stand is not None:
                    self._stand.stop()
                elif self._lift is not None and self._lift.phase is not None:
                    self._lift.request_lower(now_s, urgent=True)
        if self._stand is not None:
            phase = self._stand.advance(now_s)
            self._progress = max(self._progress, _STAND_SHARE * self._stand.progress)
            if phase is not _STAND_DONE:
                return StepResult.running(self._feedback(now_s, "standing"))
            self._stand = None
            if self._abort_reason:
                return StepResult.aborted(HighFiveResult(success=False, message=(
                    f"aborted: {self._abort_reason}")), self._feedback(now_s, "aborted"))
            if self._cancel_reason:
                return self._canceled(now_s)
            try:
                self._lift.start(now_s)
            except WbcError as err:
                return StepResult.aborted(HighFiveResult(success=False, message=str(err)))
        lift = self._lift
        if lift.phase is None:  # canceled before the lift began
            return self._canceled(now_s)
        if not self._abort_reason and not self._cancel_reason and lift.phase in _WATCHED:
            problem = self.context.balance_problem()
            if problem:
                self._abort_reason = f"balance was being lost ({problem})"
                lift.request_lower(now_s, urgent=True)
        phase = lift.advance(now_s)
        start = _STAND_SHARE if self._stood else 0.0
        self._progress = max(self._progress, start + (1.0 - start) * lift.progress)
        if phase is not _DONE:
            return StepResult.running(self._feedback(now_s, PHASE_NAMES[phase]))
        if self._abort_reason:
            return StepResult.aborted(HighFiveResult(success=False, message=(
                f"aborted: {self._abort_reason}; {self._end_state()}")),
                self._feedback(now_s, "aborted"))
        if self._cancel_reason:
            return self._canceled(now_s)
        return StepResult.succeeded(HighFiveResult(success=True, message=(
            f"high five done: foot raised to {lift.height_m:.3f} m, held "
            f"{self.goal.hold_seconds} s, back on four feet")), self._feedback(now_s, "complete"))

    def _end_state(self) -> str:
        """What state the unwind left the robot in, as measured."""
        context = self.context
        if context.is_standing():
            return "the foot was put down and the robot is back on four feet"
        return (f"the foot was put down but the robot is not standing (base height "
                f"{context.q[2]:.2f} m, tilt {context.tilt_deg():.0f} deg)")

    def cancel(self, now_s: float, reason: str) -> None:
        self._cancel_reason = reason
        if self._stand is not None:
            self._stand.stop()
        elif self._lift is not None and self._lift.phase is not None:
            self._lift.request_lower(now_s)

    def _canceled(self, now_s: float) -> StepResult[HighFiveResult, HighFiveFeedback]:
        return StepResult.canceled(HighFiveResult(success=False, message=(
            f"canceled ({self._cancel_reason}): the foot is down and the robot is back on "
            "four feet")), self._feedback(now_s, "canceled"))

    def abort_result(self, message: str) -> HighFiveResult:
        return HighFiveResult(success=False, message=message)

    def _feedback(self, now_s: float, phase: str) -> HighFiveFeedback | None:
        """Feedback at a phase change, else at the throttle's period."""
        if not self._throttle.due(now_s, phase):
            return None
        if phase in ("complete", "canceled", "aborted"):
            self._progress = 1.0
        return HighFiveFeedback(phase=phase, progress=float(self._progress))
