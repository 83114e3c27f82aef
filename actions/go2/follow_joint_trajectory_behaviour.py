"""FollowJointTrajectory (control_msgs semantics) for the joints of one GO2 leg.

A standing robot cannot move the joints of a leg that carries weight, so a goal names the
joints of one leg only (any subset, any order). If that leg is in stance, the behaviour first
releases it (:class:`~wbc.motions.leg_lift.LegLift` with ``release_only``: the centre of mass shifts
into the other three feet's triangle, the foot is unloaded and set to swing); the trajectory
then starts from the leg's measured state, and ``time_from_start`` counts from the moment the
leg is free. While the trajectory runs the leg is driven in joint space: its foot task is
switched off and the posture task tracks the interpolated joint positions, velocities and
accelerations with a raised weight.

Rejections: a goal that fails validation is rejected by the goal callback with the
FollowJointTrajectory error code as the rejection code (``Rejection.code`` is
``FollowJointTrajectoryResult.INVALID_JOINTS`` (-2), ``INVALID_GOAL`` (-1) or
``OLD_HEADER_TIMESTAMP`` (-3)), and the message names the field, what was received and what
is valid. A client sees them as ``GoalRejectedError.rejection.code`` / ``.message`` (or
``goal_handle.rejection``). The same checks run again when the goal starts (the robot may
have changed while it was queued); a failure then ends the goal ABORTED with the code in
``result.error_code``. Failures during execution end ABORTED with
``PATH_TOLERANCE_VIOLATED`` (-4) or ``GOAL_TOLERANCE_VIOLATED`` (-5); success is
``SUCCESSFUL`` (0), with an ``error_string`` that says the goal was reached and what state it
leaves the robot in (joint_trajectory_controller also fills it on success). A canceled goal, as
in ROS 2's joint_trajectory_controller, has ``error_code`` 0; its status says CANCELED.

After the goal ends, however it ends (except a cancel during the release), the foot stays
up: the leg stays in swing, holding where it stopped, and the robot stands on the other three
feet. Its joint targets are frozen and its foot task holds the foot there (the same joint
configuration), so that a later Stand (or Sit) puts the foot down as it does for any foot in
the air; the result's ``error_string`` says so. A later FollowJointTrajectory goal for the same
leg starts at once, without a release. (control_msgs' goal has no field to ask for the foot to
be put down at the end, and this server adds none.)

Feedback, as control_msgs defines it, has no phase: ``header.stamp`` is the robot time and
``header.frame_id`` is empty (as ros2_controllers' joint_trajectory_controller leaves it);
``desired``, ``actual`` and ``error`` are the goal's joints. ``desired.time_from_start`` is the
trajectory time reached: 0 while the leg is being released and until a future
``header.stamp``, then advancing with the clock, and beyond the last point's time while the
goal tolerance is awaited. Feedback comes at every change of this server's internal phase
(:data:`PHASES`) and at least every 20 ms.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from actions.behaviour import Behaviour, StepResult
from actions.feedback_throttle import FeedbackThrottle
from actions.go2.joint_spline import JointSpline
from actions.go2.robot_context import RobotContext
from actions.go2.trajectory_plan import (
    DEFAULT_GOAL_TOLERANCE_RAD,
    DEFAULT_PATH_TOLERANCE_RAD,
    INVALID_GOAL,
    InvalidTrajectoryError,
    Result,
    TrajectoryPlan,
    check_robot,
    plan_trajectory,
)
from actions.messages import Duration, Time
from actions.responses import GoalResponse, Rejection
from actions.ros_interfaces.control_msgs import (
    FollowJointTrajectoryFeedback,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
)
from actions.ros_interfaces.std_msgs import Header
from actions.ros_interfaces.trajectory_msgs import JointTrajectoryPoint
from wbc.controller.foot_reach import LEG_REACH_M
from wbc.model.description import JOINT_NAMES, LEGS, Go2Description
from wbc.motions.leg_lift import LegLift, LiftPhase

#: Multiplier of the posture weight on the moving leg's joints. Measured (1 s move of the
#: three FR joints by up to 1.1 rad): final error 2.5 mrad at 1, 0.2 mrad at 10, below
#: 0.05 mrad from 100 on; the peak error during the move is 2.7 mrad from 10 on.
TRACKING_WEIGHT = 100.0
#: Internal phase names of the release.
RELEASE_PHASES = {LiftPhase.SHIFTING: "shifting", LiftPhase.UNLOADING: "unloading"}
#: Every internal phase, in order. Not in the feedback (control_msgs' has no phase field): a
#: change of phase publishes a feedback message at once.
PHASES = ("shifting", "unloading", "waiting", "following", "settling", "succeeded", "aborted",
          "canceled")


def validate_follow_joint_trajectory_goal(
        context: RobotContext, goal: FollowJointTrajectoryGoal) -> GoalResponse | Rejection:
    """The goal callback: ACCEPT, or a :class:`Rejection` whose code is the FJT error code."""
    try:
        check_robot(context, plan_trajectory(goal), context.now_s)
    except InvalidTrajectoryError as err:
        return Rejection(err.code, str(err))
    return GoalResponse.ACCEPT



class FollowJointTrajectoryBehaviour(
        Behaviour[FollowJointTrajectoryGoal, FollowJointTrajectoryResult,
                  FollowJointTrajectoryFeedback]):
    """Releases the leg if it is in stance, then follows the trajectory in joint space.

    Interpolation from the leg's measured state (at rest) through the points:

    - positions only: a quintic spline with zero velocity and acceleration at both ends (for
      one point, the minimum-jerk profile); it passes through the points without stopping;
    - positions and velocities: cubic Hermite segments through them;
    - positions, velocities and accelerations: quintic Hermite segments.

    After the last point the targets hold its positions at zero velocity. The controller's
    joint position and velocity limits bound any overshoot between the points.

    Cancel: while the leg is being released, the release unwinds (the foot is reloaded, the
    centre of mass goes back) and the goal ends CANCELED on four feet; afterwards the leg
    holds its measured position and the goal ends CANCELED at once.

    Args:
        context: The robot's shared context.
        tracking_weight: Multiplier of the posture weight on the leg's joints.
    """

    def __init__(self, context: RobotContext, *, tracking_weight: float = TRACKING_WEIGHT):
        self.context = context
        self.tracking_weight = tracking_weight
        self._plan: TrajectoryPlan | None = None
        self._failure: FollowJointTrajectoryResult | None = None
        self._lift: LegLift | None = None
        self._spline: JointSpline | None = None
        self._t0 = math.inf  # trajectory time 0 [s], once the leg is free
        self._holds_leg = False
        self._cancel_reason = ""
        self._throttle = FeedbackThrottle()

    def start(self, goal: FollowJointTrajectoryGoal, now_s: float) -> None:
        try:
            plan = plan_trajectory(goal)
            check_robot(self.context, plan, now_s)
        except InvalidTrajectoryError as err:
            self._failure = Result(error_code=err.code, error_string=str(err))
            return
        self._plan = plan
        self._leg_indices = np.array(Go2Description.default().leg_joint_indices(plan.leg))
        if self.context.controller.schedule.is_stance(plan.leg):
            self._lift = LegLift(self.context.controller, leg=plan.leg, release_only=True)
            self._lift.start(now_s)
        else:
            self._take_leg(now_s)

    def step(self, now_s: float) -> StepResult[FollowJointTrajectoryResult,
                                                FollowJointTrajectoryFeedback]:
        if self._failure is not None:
            return StepResult.aborted(self._failure)
        plan = self._plan
        if self._lift is not None:
            phase = self._lift.advance(now_s)
            if phase is not LiftPhase.DONE:
                actual = self._measured()
                return StepResult.running(self._feedback(
                    now_s, RELEASE_PHASES.get(phase, phase.value), 0.0, actual[0], actual))
            self._lift = None
            if self._cancel_reason:
                return StepResult.canceled(Result(error_string=(
                    f"canceled ({self._cancel_reason}) while the {plan.leg} leg was being "
                    "released: the foot is loaded again, four feet in stance")))
            self._take_leg(now_s)
        t = now_s - self._t0
        actual = self._measured()
        if self._cancel_reason:
            return StepResult.canceled(Result(error_string=(
                f"canceled ({self._cancel_reason}) at t={t:.3f} s of the trajectory: "
                f"{_left_in_swing(plan.leg, 'where it was')}")),
                self._feedback(now_s, "canceled", t, self._hold, actual))
        return self._track(now_s, t, actual)

    def _track(self, now_s: float, t: float, actual: tuple[np.ndarray, np.ndarray]
               ) -> StepResult[FollowJointTrajectoryResult, FollowJointTrajectoryFeedback]:
        """Command the trajectory at time ``t`` [s] and judge the tracking against tolerances."""
        plan = self._plan
        desired = self._spline.sample(t)
        self._command(*desired)
        if t < 0.0:
            return StepResult.running(self._feedback(now_s, "waiting", t, desired, actual))
        moving = t <= plan.duration_s
        if moving:
            tolerances = plan.path_tolerance, plan.path_velocity_tolerance
        else:
            tolerances = plan.goal_tolerance, plan.goal_velocity_tolerance
        violation = _violation(desired[0] - actual[0], desired[1] - actual[1], *tolerances,
                               plan.joint_names)
        late = t - plan.duration_s
        if not violation and not moving:
            self._release_leg(desired[0])
            return StepResult.succeeded(
                Result(error_string=f"goal reached: {_left_in_swing(plan.leg, 'the last point')}"),
                self._feedback(now_s, "succeeded", t, desired, actual))
        if not violation or (not moving and late <= plan.goal_time_tolerance_s):
            phase = "following" if moving else "settling"
            return StepResult.running(self._feedback(now_s, phase, t, desired, actual))
        self._release_leg(actual[0])
        if moving:
            code, field, default = Result.PATH_TOLERANCE_VIOLATED, "path_tolerance", (
                DEFAULT_PATH_TOLERANCE_RAD)
            when = f"path tolerance violated at t={t:.3f} s of the trajectory"
        else:
            code, field, default = Result.GOAL_TOLERANCE_VIOLATED, "goal_tolerance", (
                DEFAULT_GOAL_TOLERANCE_RAD)
            when = (f"goal tolerance violated {late:.3f} s after the last point's time "
                    f"(goal_time_tolerance {plan.goal_time_tolerance_s:g} s)")
        return StepResult.aborted(Result(error_code=code, error_string=(
            f"{when}: {violation} ({field}; 0 = the default {default:g} rad, -1 = no limit); "
            f"{_left_in_swing(plan.leg, 'where it was')}")),
            self._feedback(now_s, "aborted", t, desired, actual))

    def cancel(self, now_s: float, reason: str) -> None:
        self._cancel_reason = reason
        if self._lift is not None:
            self._lift.request_lower(now_s)
        elif self._holds_leg:
            self._release_leg(self._measured()[0])

    def abort_result(self, message: str) -> FollowJointTrajectoryResult:
        if self._holds_leg:  # the framework ends the goal: freeze the leg where it is
            self._release_leg(self._measured()[0])
        return Result(error_code=INVALID_GOAL, error_string=message)

    # ------------------------------------------------------------------ the leg

    def _measured(self) -> tuple[np.ndarray, np.ndarray]:
        """Measured positions [rad] and velocities [rad/s] of the goal's joints."""
        indices = self._plan.joint_indices
        return self.context.q[7 + indices].copy(), self.context.v[6 + indices].copy()

    def _take_leg(self, now_s: float) -> None:
        """Hand the free leg to the posture task; the trajectory starts from where it is."""
        ctrl, plan = self.context.controller, self._plan
        joints = self.context.q[7:]
        self._leg_hold = joints[self._leg_indices].copy()  # joints the goal does not name
        start = joints[plan.joint_indices].copy()
        self._spline = JointSpline(plan, start)
        self._t0 = max(now_s, plan.stamp_s)
        self._hold = start
        ctrl.set_foot_weight(plan.leg, 0.0)
        weights = np.ones(len(JOINT_NAMES))
        weights[self._leg_indices] = self.tracking_weight
        ctrl.set_posture_weights(weights)
        self._holds_leg = True
        self._command(start, np.zeros_like(start), np.zeros_like(start))

    def _command(self, positions: np.ndarray, velocities: np.ndarray,
                 accelerations: np.ndarray) -> None:
        """Posture targets: the goal's joints as given, the rest of the leg held, others kept."""
        ctrl, indices = self.context.controller, self._plan.joint_indices
        target = ctrl.posture_target
        target[self._leg_indices] = self._leg_hold
        target[indices] = positions
        velocity = np.zeros(len(JOINT_NAMES))
        acceleration = np.zeros(len(JOINT_NAMES))
        velocity[indices], acceleration[indices] = velocities, accelerations
        ctrl.set_posture_target(target, velocity, acceleration)

    def _release_leg(self, positions: np.ndarray) -> None:
        """Hold ``positions`` and give the swinging leg back to its foot task, in place.

        The foot task then holds the foot where the joints put it (the same configuration),
        which is what a later Stand expects of a foot in the air: it moves the foot target.
        """
        ctrl, leg = self.context.controller, self._plan.leg
        self._hold = np.array(positions, dtype=float)
        zeros = np.zeros_like(self._hold)
        self._command(self._hold, zeros, zeros)
        ctrl.set_posture_weights(np.ones(len(JOINT_NAMES)))
        shoulder = ctrl.shoulder_position(leg)
        offset = ctrl.foot_positions()[LEGS.index(leg)] - shoulder
        reach = 0.999 * LEG_REACH_M  # set_foot_target refuses targets beyond the reach
        distance = float(np.linalg.norm(offset))
        if distance > reach:
            offset *= reach / distance
        ctrl.set_foot_target(leg, shoulder + offset)
        ctrl.set_foot_weight(leg)  # the configured weight
        self._holds_leg = False

    # ------------------------------------------------------------------ feedback

    def _feedback(self, now_s: float, phase: str, t: float, desired: Any,
                  actual: tuple[np.ndarray, np.ndarray]) -> FollowJointTrajectoryFeedback | None:
        """Feedback at a phase change, else at the throttle's period.

        ``desired`` is ``(positions, velocities, accelerations)`` or positions alone (held).
        """
        if not self._throttle.due(now_s, phase):
            return None
        if isinstance(desired, np.ndarray):
            desired = (desired, np.zeros_like(desired), np.zeros_like(desired))
        when = Duration.from_seconds(max(t, 0.0))
        return FollowJointTrajectoryFeedback(
            header=Header(stamp=Time.from_seconds(now_s)),
            joint_names=list(self._plan.joint_names),
            desired=JointTrajectoryPoint(positions=desired[0], velocities=desired[1],
                                         accelerations=desired[2], time_from_start=when),
            actual=JointTrajectoryPoint(positions=actual[0], velocities=actual[1],
                                        time_from_start=when),
            error=JointTrajectoryPoint(positions=desired[0] - actual[0],
                                       velocities=desired[1] - actual[1],
                                       time_from_start=when))


def _left_in_swing(leg: str, where: str) -> str:
    """What a goal that ends with the leg free leaves the robot in, and what puts it back."""
    return (f"the {leg} leg holds {where}, in swing: the {leg} foot stays up and the robot "
            f"stands on three feet; a Stand goal puts the foot down")


def _violation(error_p: np.ndarray, error_v: np.ndarray, tolerance_p: np.ndarray,
               tolerance_v: np.ndarray, names: tuple[str, ...]) -> str:
    """The first joint outside its tolerance, as text ('' when all are within)."""
    for errors, tolerances, what, unit in ((error_p, tolerance_p, "position", "rad"),
                                           (error_v, tolerance_v, "velocity", "rad/s")):
        outside = np.flatnonzero(np.abs(errors) > tolerances)
        if outside.size:
            j = int(outside[0])
            return (f"{names[j]} {what} error {errors[j]:+.4f} {unit} exceeds its tolerance "
                    f"{tolerances[j]:g} {unit}")
    return ""
