"""Walk: trot at a velocity for a duration or a distance (or as the streamed ``cmd_vel``
steers), then stop on four loaded feet."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from actions.behaviour import Behaviour, StepResult
from actions.feedback_throttle import FeedbackThrottle
from actions.go2.go2_interfaces import WalkFeedback, WalkGoal, WalkResult
from actions.go2.high_five_behaviour import ROBOT_NOT_READY
from actions.go2.robot_context import TILT_LIMIT_DEG, RobotContext
from actions.go2.velocity_stream import VelocityCommand
from actions.responses import GoalResponse, Rejection
from wbc.controller.balance_controller import BalanceController
from wbc.core.errors import WbcError
from wbc.locomotion.walking import Walking
from wbc.motions.posture_transition import PostureTransition, TransitionPhase

#: Longest walk [s] a goal may ask for (a distance too, at the goal's speed).
MAX_WALK_S = 300.0
#: Longest path [m] a goal may ask for.
MAX_DISTANCE_M = 100.0
#: Slowest translation [m/s] a distance goal may ask for.
MIN_SPEED_MPS = 0.02
#: Rejection codes of Walk goals (beside the runner's own, 1 to 4, and the robot's 12).
INVALID_VELOCITY, INVALID_DURATION, INVALID_DISTANCE = 30, 31, 32
#: Rejection code of a goal other than a walk while the robot walks.
ROBOT_WALKING = 33
#: Below this base height [m] while walking the balance is being lost.
MIN_WALKING_HEIGHT_M = 0.18
#: Longest stop [s] (from the request to four loaded feet) before the goal ends ABORTED.
MAX_STOP_S = 2.0
#: The cosine of the tilt limit, a hair inside it: a base tilted less (its vertical axis'
#: z component above it) is level enough without computing its angle.
_LEVEL_COS = math.cos(math.radians(TILT_LIMIT_DEG)) + 1e-9
#: Consecutive damping fallbacks [ticks] after which the goal ends at once.
FAULT_LIMIT_TICKS = 50
#: After the last step the goal ends once the base is slower than ``REST_SPEED_MPS`` [m/s]
#: (the estimate) and ``SETTLE_S`` [s] has passed, or after ``MAX_SETTLE_S`` [s]: the walking
#: motion is done when its last foot is commanded loaded, and on the simulated GO2 that foot
#: was seen to carry its load about 0.1 s later.
REST_SPEED_MPS, SETTLE_S, MAX_SETTLE_S = 0.05, 0.15, 0.5
#: The shared "goes on, no feedback" step result (what ``StepResult.running()`` returns).
_GOES_ON: StepResult[WalkResult, WalkFeedback] = StepResult.running()


class WalkingMotion(Protocol):
    """What the behaviour uses of :class:`wbc.locomotion.Walking` (the walking motion)."""

    phase: Any
    measured_velocity: np.ndarray

    @property
    def distance_m(self) -> float: ...

    @property
    def gait_phase(self) -> float: ...

    def start(self, now_s: float) -> None: ...

    def set_velocity(self, forward_mps: float, lateral_mps: float,
                     yaw_rate_radps: float) -> None: ...

    def request_stop(self, now_s: float) -> None: ...

    def advance(self, now_s: float) -> Any: ...


def default_walking(controller: BalanceController) -> WalkingMotion:
    """The library's walking motion on ``controller`` (:class:`wbc.locomotion.Walking`, its
    default gait and limits: those the velocity stream and the goal check use)."""
    return Walking(controller)


def validate_walk_goal(context: RobotContext, goal: WalkGoal) -> GoalResponse | Rejection:
    """The goal callback: ACCEPT, or a coded rejection naming the field, the value received
    and what is valid."""
    problem = context.velocity_stream.limits.problem(goal.forward_mps, goal.lateral_mps,
                                                     goal.yaw_rate_radps)
    if problem:
        return Rejection(INVALID_VELOCITY, problem)
    duration, distance = goal.duration_s, goal.distance_m
    for name, value, limit, unit, code in (
            ("duration_s", duration, MAX_WALK_S, "s", INVALID_DURATION),
            ("distance_m", distance, MAX_DISTANCE_M, "m", INVALID_DISTANCE)):
        if not isinstance(value, (int, float)) or not math.isfinite(value) or not (
                0.0 <= value <= limit):
            return Rejection(code, (
                f"{name}: expected a {'duration' if unit == 's' else 'path length'} in "
                f"[0, {limit:g}] {unit}, received {value!r}"))
    if (duration > 0.0) == (distance > 0.0):
        return Rejection(INVALID_DURATION, (
            f"duration_s, distance_m: expected exactly one of them above 0 (walk for a time or "
            f"for a path length), received duration_s={duration!r}, distance_m={distance!r}"))
    if distance > 0.0:
        speed = math.hypot(goal.forward_mps, goal.lateral_mps)
        if speed < MIN_SPEED_MPS or distance / speed > MAX_WALK_S:
            return Rejection(INVALID_DISTANCE, (
                f"distance_m: {distance:g} m at {speed:.3g} m/s would take "
                f"{distance / speed if speed > 0 else math.inf:.3g} s; expected a forward and "
                f"lateral speed of at least {MIN_SPEED_MPS:g} m/s and at most {MAX_WALK_S:g} s "
                "of walking"))
    if not context.is_upright():
        return Rejection(ROBOT_NOT_READY, (
            f"robot not able: base tilt {context.tilt_deg():.0f} deg, height {context.q[2]:.2f} m;"
            " it must be upright (send a Stand goal once it is)"))
    return GoalResponse.ACCEPT


class WalkBehaviour(Behaviour[WalkGoal, WalkResult, WalkFeedback]):
    """Stand first if needed; walk at the goal's velocity until its duration has passed or
    its distance is travelled; stop on four loaded feet.

    A goal the velocity stream sent (:meth:`~actions.go2.velocity_stream.VelocityStream.claim`)
    follows the stream instead: each newer command steers, a zero command or the command's
    timeout (robot time) stops it. A cancel stops it (CANCELED on four loaded feet). A
    controller fault, a base tilt above 12 deg or a base below 0.18 m stops it too, and the
    goal ends ABORTED with the reason; a fault lasting ``FAULT_LIMIT_TICKS`` ends it at once.

    Args:
        context: The robot's shared context.
        make_walking: Makes the walking motion on the controller (default
            :func:`default_walking`; tests give a scripted one).
    """

    def __init__(self, context: RobotContext, *,
                 make_walking: Callable[[BalanceController], WalkingMotion] | None = None):
        self.context = context
        #: The walking motion this goal drives (made now, started once the robot stands).
        self.walking: WalkingMotion = (make_walking or default_walking)(context.controller)
        self._stand: PostureTransition | None = None
        self._stream = False
        self._seen: VelocityCommand | None = None
        self._stamp_s = 0.0  # robot time [s] the newest stream command was first seen
        self._walk_start_s = math.nan
        self._stop_s = math.nan
        self._stopping = False  # a stop was requested (at _stop_s)
        self._stop_distance_m = 0.0  # the path [m] walked when the stop was asked
        self._done_s = math.nan  # robot time [s] the walking motion was done
        self._stop_why = ""  # why the walk stops: its aim reached, the stream's stop
        self._cancel_reason = ""
        self._abort_reason = ""
        self._progress = 0.0
        self._throttle = FeedbackThrottle()
        self._names: dict[Any, str] = {}  # the walking motion's phases by their names

    # -- the behaviour's interface ----------------------------------------------------------

    def start(self, goal: WalkGoal, now_s: float) -> None:
        self.goal = goal
        context = self.context
        self._stream = context.velocity_stream.claim(goal)
        context.walking = "the velocity stream (cmd_vel)" if self._stream else "a walk goal"
        if self._stream:
            self._seen = context.velocity_stream.latest()
            self._stamp_s = now_s
        if not context.is_standing():
            self._stand = PostureTransition(context.controller, "standing", duration_s=1.5)
            self._stand.start(now_s)
        else:
            self._begin(now_s)

    def step(self, now_s: float) -> StepResult[WalkResult, WalkFeedback]:
        context = self.context
        fault = context.fault
        if fault:
            if context.consecutive_fallbacks >= FAULT_LIMIT_TICKS:
                return self._end("aborted", now_s, (
                    f"aborted: controller fault for {context.consecutive_fallbacks} ticks "
                    f"({fault}); the controller holds the joints with damping while it lasts"))
            self._stop_for_abort(now_s, f"controller fault ({fault})")
        if self._stand is not None:
            if self._stand.advance(now_s) is not TransitionPhase.DONE:
                return StepResult.running(self._feedback(now_s, "standing"))
            self._stand = None
            if self._abort_reason:
                return self._end("aborted", now_s, f"aborted: {self._abort_reason}")
            if self._cancel_reason:
                return self._end("canceled", now_s, (
                    f"canceled ({self._cancel_reason}) before walking: the stand-up stopped "
                    "where it was"))
            try:
                self._begin(now_s)
            except WbcError as err:
                return self._end("aborted", now_s, f"aborted: {err}")
        if not self._stopping:
            # The balance watch's common case inline (clearly level and high: no angle).
            q = context.q
            x, y = q.item(3), q.item(4)
            problem = "" if (1.0 - 2.0 * (x * x + y * y) > _LEVEL_COS
                             and q.item(2) >= MIN_WALKING_HEIGHT_M) else self._balance_problem()
            if problem:
                self._stop_for_abort(now_s, f"balance was being lost ({problem})")
            elif self._stream:
                self._follow_stream(now_s)
            else:
                self._check_aim(now_s)
        phase = self.walking.advance(now_s)
        name = self._names.get(phase)
        if name is None:  # a phase not seen yet (a few per walk): its name, once
            name = self._names[phase] = str(getattr(phase, "name", phase)).lower()
        if name != "done":
            if self._stopping and now_s - self._stop_s > MAX_STOP_S:
                return self._end("aborted", now_s, (
                    f"aborted: not on four loaded feet {MAX_STOP_S:g} s after the stop"
                    + (f" ({self._abort_reason})" if self._abort_reason else "")))
            if not self._throttle.due(now_s, name):  # most ticks: no feedback
                return _GOES_ON
            return StepResult.running(self._make_feedback(now_s, name))
        if math.isnan(self._done_s):
            self._done_s = now_s
        settled_s = now_s - self._done_s
        if settled_s < MAX_SETTLE_S - 1e-9 and (
                settled_s < SETTLE_S - 1e-9 or self._speed() >= REST_SPEED_MPS):
            return StepResult.running(self._feedback(now_s, "stopping"))
        return self._finished(now_s)

    def cancel(self, now_s: float, reason: str) -> None:
        self._cancel_reason = reason
        if self._stand is not None:
            self._stand.stop()
        else:
            self._request_stop(now_s)

    def abort_result(self, message: str) -> WalkResult:
        self._release()
        return WalkResult(success=False, message=message, distance_m=self._distance())

    # -- the walk ---------------------------------------------------------------------------

    def _begin(self, now_s: float) -> None:
        """Start walking at the goal's (or the stream's) velocity."""
        walking = self.walking
        walking.start(now_s)
        self._walk_start_s = now_s
        command = self._seen
        if self._stream and command is not None:
            walking.set_velocity(command.forward_mps, command.lateral_mps,
                                 command.yaw_rate_radps)
        else:
            goal = self.goal
            walking.set_velocity(goal.forward_mps, goal.lateral_mps, goal.yaw_rate_radps)

    def _request_stop(self, now_s: float) -> None:
        if not self._stopping and self._walk_started:
            self._stop_s, self._stop_distance_m = now_s, self._distance()
            self._stopping = True
            self.walking.request_stop(now_s)

    @property
    def _walk_started(self) -> bool:
        return not math.isnan(self._walk_start_s)

    def _stop_for_abort(self, now_s: float, reason: str) -> None:
        if not self._abort_reason:
            self._abort_reason = reason
            if self._stand is not None:
                self._stand.stop()
            else:
                self._request_stop(now_s)

    def _check_aim(self, now_s: float) -> None:
        """Stop once the goal's duration has passed or its distance is travelled."""
        duration = self.goal.duration_s
        progress = ((now_s - self._walk_start_s) / duration if duration > 0.0
                    else self.walking.distance_m / self.goal.distance_m)
        if not progress <= self._progress:  # it grew (NaN too: done, as min(1, NaN) said)
            self._progress = progress if progress < 1.0 else 1.0
        if self._progress >= 1.0 - 1e-9:
            self._stop_why = "aim"
            self._request_stop(now_s)

    def _follow_stream(self, now_s: float) -> None:
        """Steer with a newer command; stop on a zero one or at the newest one's timeout."""
        stream = self.context.velocity_stream
        latest = stream.latest()
        if latest is not None and (self._seen is None or latest.sequence != self._seen.sequence):
            self._seen, self._stamp_s = latest, now_s
            if latest.is_zero:
                self._stop_why = "a zero velocity command"
                self._request_stop(now_s)
                return
            self.walking.set_velocity(latest.forward_mps, latest.lateral_mps,
                                      latest.yaw_rate_radps)
        timeout = self._seen.timeout_s if self._seen is not None else stream.timeout_s
        if now_s - self._stamp_s >= timeout - 1e-9:
            self._stop_why = f"no velocity command for {timeout:g} s (its timeout)"
            self._request_stop(now_s)

    def _balance_problem(self) -> str:
        """Why the walk must stop ('' when it need not): a tilt or a sinking base. (The
        step tests the common case first: clearly level and high.)"""
        tilt = self.context.tilt_deg()
        if tilt > TILT_LIMIT_DEG:
            return f"base tilt {tilt:.1f} deg above {TILT_LIMIT_DEG:.0f} deg"
        height = float(self.context.q[2])
        if height < MIN_WALKING_HEIGHT_M:
            return f"base height {height:.3f} m below {MIN_WALKING_HEIGHT_M:.2f} m"
        return ""

    def _finished(self, now_s: float) -> StepResult[WalkResult, WalkFeedback]:
        """The walk is over (the motion is DONE): the goal's end."""
        distance = self._distance()
        feet = self._loaded_feet()
        if self._abort_reason:
            return self._end("aborted", now_s, (
                f"aborted: {self._abort_reason}; stopped after {distance:.2f} m, {feet}"))
        if self._cancel_reason:
            return self._end("canceled", now_s, (
                f"canceled ({self._cancel_reason}): stopped after {distance:.2f} m, {feet}"))
        walked_s = self._stop_s - self._walk_start_s
        why = f"stopped: {self._stop_why}" if self._stream else (
            f"walked {walked_s:.2f} s" if self.goal.duration_s > 0.0 else
            f"walked {self._stop_distance_m:.2f} m of {self.goal.distance_m:g} m")
        return self._end("complete", now_s, (
            f"walk done: {why}, {distance:.2f} m in all, {feet}"), success=True)

    def _speed(self) -> float:
        """The base's horizontal speed [m/s] (the state estimate)."""
        v = self.context.v
        return math.hypot(v.item(0), v.item(1))

    def _loaded_feet(self) -> str:
        """The feet the controller loads at the end, and the base's speed, in words."""
        legs = self.context.controller.schedule.support_legs()
        feet = "on four loaded feet" if len(legs) == 4 else (
            f"on {len(legs)} loaded feet ({', '.join(legs)})")
        speed = self._speed()
        return feet if speed < REST_SPEED_MPS else f"{feet}, base still at {speed:.2f} m/s"

    def _distance(self) -> float:
        return float(self.walking.distance_m) if self._walk_started else 0.0

    def _end(self, phase: str, now_s: float, message: str, *,
             success: bool = False) -> StepResult[WalkResult, WalkFeedback]:
        """The goal's terminal step: ``phase`` is ``complete``, ``canceled`` or ``aborted``."""
        self._release()
        self._progress = 1.0 if phase == "complete" else self._progress
        result = WalkResult(success=success, message=message, distance_m=self._distance())
        feedback = self._feedback(now_s, phase, force=True)
        if phase == "complete":
            return StepResult.succeeded(result, feedback)
        if phase == "canceled":
            return StepResult.canceled(result, feedback)
        return StepResult.aborted(result, feedback)

    def _release(self) -> None:
        """Other goals may run again; a newer streamed command may start the next walk."""
        self.context.walking = ""
        if self._stream:
            self.context.velocity_stream.stopped_at(self._seen)

    def _feedback(self, now_s: float, phase: str, *, force: bool = False) -> WalkFeedback | None:
        """Feedback at a phase change, else at the throttle's period."""
        if not self._throttle.due(now_s, phase) and not force:
            return None
        return self._make_feedback(now_s, phase)

    def _make_feedback(self, now_s: float, phase: str) -> WalkFeedback:
        """The feedback now, in ``phase``."""
        walking = self.walking
        started = self._walk_started
        forward, lateral, yaw_rate = (walking.measured_velocity.tolist() if started
                                      else (0.0, 0.0, 0.0))
        return WalkFeedback(
            phase=phase, progress=float(self._progress),
            gait_phase=float(walking.gait_phase) if started else 0.0,
            distance_m=self._distance(), forward_mps=float(forward),
            lateral_mps=float(lateral), yaw_rate_radps=float(yaw_rate))


def stream_goal(command: VelocityCommand) -> WalkGoal:
    """The walk goal the velocity stream sends for ``command`` (its duration, the longest a
    goal may ask for, is not used: the stream stops the walk)."""
    return WalkGoal(forward_mps=command.forward_mps, lateral_mps=command.lateral_mps,
                    yaw_rate_radps=command.yaw_rate_radps, duration_s=MAX_WALK_S)
