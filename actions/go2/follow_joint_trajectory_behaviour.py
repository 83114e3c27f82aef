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
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np

# scipy's splines are well tested, including the end conditions and Hermite data we need;
# a hand-written banded solve would buy nothing.
from scipy.interpolate import BPoly, make_interp_spline

from actions.behaviour import Behaviour, StepResult
from actions.feedback_throttle import FeedbackThrottle
from actions.go2.robot_context import STANDING_HEIGHT_M, RobotContext
from actions.messages import (
    Duration,
    FollowJointTrajectoryFeedback,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    Header,
    JointTolerance,
    JointTrajectoryPoint,
    Time,
)
from actions.responses import GoalResponse, Rejection
from wbc.controller.contact_modes import LEG_REACH_M
from wbc.controller.controller_config import ControllerConfig
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS, Go2Description
from wbc.motions.leg_lift import LegLift, LiftPhase

Result = FollowJointTrajectoryResult
INVALID_GOAL, INVALID_JOINTS = Result.INVALID_GOAL, Result.INVALID_JOINTS

#: Path tolerance [rad] of a joint whose ``path_tolerance`` entry is 0 or missing. Measured
#: peak tracking error: 2.5 mrad for 1 to 3 s moves, 7 mrad for a 0.3 s move at 2.9 rad/s.
DEFAULT_PATH_TOLERANCE_RAD = 0.1
#: Goal tolerance [rad] of a joint whose ``goal_tolerance`` entry is 0 or missing.
DEFAULT_GOAL_TOLERANCE_RAD = 0.02
#: Time [s] after the last point's time to reach the goal tolerance when
#: ``goal_time_tolerance`` is 0.
DEFAULT_GOAL_TIME_TOLERANCE_S = 0.5
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
#: Largest base tilt [deg] at which a goal is accepted.
MAX_TILT_DEG = 5.0

_LEG_OF_JOINT = {name: name.split("_", 1)[0] for name in JOINT_NAMES}
_VALID_JOINTS = ", ".join(JOINT_NAMES)
_NO_LIMIT = -1.0


class InvalidTrajectoryError(ConfigurationError):
    """A goal this server cannot run.

    Attributes:
        code: The ``FollowJointTrajectoryResult`` error code (``INVALID_GOAL``,
            ``INVALID_JOINTS`` or ``OLD_HEADER_TIMESTAMP``).
    """

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


@dataclass(frozen=True)
class TrajectoryPlan:
    """A validated goal, as arrays in the goal's joint order.

    Attributes:
        leg: The leg whose joints move.
        joint_names: The goal's joint names.
        joint_indices: Their indices in the description order (:data:`JOINT_NAMES`).
        times_s: ``time_from_start`` of each point [s] (n,), strictly increasing, > 0.
        positions: (n, k) [rad].
        velocities: (n, k) [rad/s], or ``None`` when the points give none.
        accelerations: (n, k) [rad/s^2], or ``None``.
        path_tolerance: Per joint (k,) position tolerance during the motion [rad]; inf: none.
        path_velocity_tolerance: The same for velocity [rad/s] (inf unless given).
        goal_tolerance: Per joint (k,) position tolerance at the end [rad].
        goal_velocity_tolerance: The same for velocity [rad/s] (inf unless given).
        goal_time_tolerance_s: How long after the last point the goal tolerance may be met.
        stamp_s: ``header.stamp`` [s]; 0 means "start as soon as the leg is free".
    """

    leg: str
    joint_names: tuple[str, ...]
    joint_indices: np.ndarray
    times_s: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None
    accelerations: np.ndarray | None
    path_tolerance: np.ndarray
    path_velocity_tolerance: np.ndarray
    goal_tolerance: np.ndarray
    goal_velocity_tolerance: np.ndarray
    goal_time_tolerance_s: float
    stamp_s: float

    @property
    def duration_s(self) -> float:
        """Time of the last point [s]."""
        return float(self.times_s[-1])


def plan_trajectory(goal: FollowJointTrajectoryGoal) -> TrajectoryPlan:
    """Check a goal's content (not the robot's state) and return it as arrays.

    Raises:
        InvalidTrajectoryError: With the error code and a message naming the field, the
            value received and what is valid.
    """
    if goal.multi_dof_trajectory.joint_names or goal.multi_dof_trajectory.points:
        _fail(INVALID_GOAL, (
            f"multi_dof_trajectory: not supported (the GO2 has no multi-DOF joints); received "
            f"{len(goal.multi_dof_trajectory.joint_names)} joint names and "
            f"{len(goal.multi_dof_trajectory.points)} points, expected an empty one"))
    for field in ("component_path_tolerance", "component_goal_tolerance"):
        if getattr(goal, field):
            _fail(INVALID_GOAL, (
                f"{field}: not supported (it applies to multi-DOF joints); received "
                f"{len(getattr(goal, field))} entries, expected none"))
    trajectory = goal.trajectory
    names = tuple(trajectory.joint_names)
    indices, leg = _check_joint_names(names)
    k = len(names)
    if not trajectory.points:
        _fail(INVALID_GOAL, "trajectory.points: empty; expected at least one point")
    points = trajectory.points
    times = np.array([point.time_from_start.to_seconds() for point in points])
    for i, time_s in enumerate(times):
        previous = 0.0 if i == 0 else times[i - 1]
        if time_s <= previous:
            after = ("0 s (the trajectory starts from the current state at time 0)" if i == 0
                     else f"points[{i - 1}].time_from_start = {previous:g} s")
            _fail(INVALID_GOAL, (
                f"trajectory.points[{i}].time_from_start: expected more than {after}, "
                f"received {time_s:g} s; times must increase strictly"))
    positions = _point_field(points, "positions", names, required=True)
    velocities = _point_field(points, "velocities", names, required=False)
    accelerations = _point_field(points, "accelerations", names, required=False)
    if accelerations is not None and velocities is None:
        _fail(INVALID_GOAL, (
            "trajectory.points[0].velocities: the points give accelerations but no "
            f"velocities; expected {k} velocities per point with the accelerations"))
    for i, point in enumerate(points):
        if point.effort:
            _fail(INVALID_GOAL, (
                f"trajectory.points[{i}].effort: not supported (the leg is position "
                f"controlled); received {len(point.effort)} values, expected none"))
    description = _description()
    _check_limits(positions, indices, names, "positions", description.position_lower,
                  description.position_upper, "rad")
    if velocities is not None:
        limit = description.velocity_limit
        _check_limits(velocities, indices, names, "velocities", -limit, limit, "rad/s")
    path, path_velocity = _tolerances(goal.path_tolerance, "path_tolerance", names,
                                      DEFAULT_PATH_TOLERANCE_RAD)
    final, final_velocity = _tolerances(goal.goal_tolerance, "goal_tolerance", names,
                                        DEFAULT_GOAL_TOLERANCE_RAD)
    goal_time = goal.goal_time_tolerance.to_seconds()
    if goal_time < 0.0:
        _fail(INVALID_GOAL, (
            f"goal_time_tolerance: expected >= 0 s (0 = the default "
            f"{DEFAULT_GOAL_TIME_TOLERANCE_S:g} s), received {goal_time:g} s"))
    return TrajectoryPlan(
        leg=leg, joint_names=names, joint_indices=indices, times_s=times, positions=positions,
        velocities=velocities, accelerations=accelerations, path_tolerance=path,
        path_velocity_tolerance=path_velocity, goal_tolerance=final,
        goal_velocity_tolerance=final_velocity,
        goal_time_tolerance_s=goal_time or DEFAULT_GOAL_TIME_TOLERANCE_S,
        stamp_s=trajectory.header.stamp.to_seconds())


def check_robot(context: RobotContext, plan: TrajectoryPlan, now_s: float) -> None:
    """Check what depends on the moment and the robot: the stamp, and that the leg can move.

    The robot must stand on four feet (the leg is then released first), or already stand on
    the three other feet with this leg in swing (left there by an earlier goal).

    Raises:
        InvalidTrajectoryError: ``OLD_HEADER_TIMESTAMP`` for a trajectory that ends in the
            past; ``INVALID_GOAL`` when the robot cannot move the leg now.
    """
    end_s = plan.stamp_s + plan.duration_s
    if plan.stamp_s > 0.0 and end_s < now_s:
        _fail(Result.OLD_HEADER_TIMESTAMP, (
            f"trajectory.header.stamp: {plan.stamp_s:g} s + the last time_from_start "
            f"{plan.duration_s:g} s = {end_s:g} s is before the robot's clock ({now_s:g} s); "
            "expected a zero stamp (start now) or one whose trajectory ends in the future"))
    controller = context.controller
    stance = controller.stance_legs
    swing = [leg for leg in LEGS if leg not in stance]
    if swing and swing != [plan.leg]:
        _fail(INVALID_GOAL, (
            f"trajectory.joint_names: cannot move the {plan.leg} leg while {', '.join(swing)} "
            f"is in swing (at most one foot may be off the ground); send a Stand goal to put "
            f"it down first, or a trajectory for {', '.join(swing)}"))
    tilt, height = context.tilt_deg(), float(context.q[2])
    if tilt > MAX_TILT_DEG or height < STANDING_HEIGHT_M:
        _fail(INVALID_GOAL, (
            f"robot not standing: base tilt {tilt:.1f} deg (at most {MAX_TILT_DEG:g}), height "
            f"{height:.3f} m (at least {STANDING_HEIGHT_M:g}); send a Stand goal first"))


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
        self._leg_indices = np.array(_description().leg_joint_indices(plan.leg))
        if plan.leg in self.context.controller.stance_legs:
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
            phase = self._lift.update(now_s)
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
        offset = ctrl.foot_position(leg) - shoulder
        reach = 0.999 * LEG_REACH_M  # set_foot_target refuses targets beyond the reach
        distance = float(np.linalg.norm(offset))
        if distance > reach:
            offset *= reach / distance
        ctrl.set_foot_target(leg, shoulder + offset)
        ctrl.set_foot_weight(leg, getattr(ctrl, "config", ControllerConfig()).foot_weight)
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


class JointSpline:
    """Positions, velocities and accelerations of the goal's joints at trajectory time t."""

    def __init__(self, plan: TrajectoryPlan, start: np.ndarray):
        times = np.concatenate([[0.0], plan.times_s])
        zeros = np.zeros_like(start)
        if plan.velocities is None:
            rest = [(1, zeros), (2, zeros)]
            spline = make_interp_spline(times, np.vstack([start, plan.positions]), k=5,
                                        bc_type=(rest, rest))
        else:
            fields = [plan.positions, plan.velocities]
            if plan.accelerations is not None:
                fields.append(plan.accelerations)
            at_start = np.array([start, *[zeros] * (len(fields) - 1)])
            at_points = [np.array([f[i] for f in fields]) for i in range(len(times) - 1)]
            spline = BPoly.from_derivatives(times, [at_start, *at_points])
        self._curves = (spline, spline.derivative(1), spline.derivative(2))
        self._start, self._end, self._duration = start, plan.positions[-1], plan.duration_s

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities, accelerations at ``t`` [s]; at rest before 0 and after the end."""
        if t <= 0.0 or t >= self._duration:
            held = self._start if t <= 0.0 else self._end
            return held.copy(), np.zeros_like(held), np.zeros_like(held)
        return tuple(np.asarray(curve(t), dtype=float) for curve in self._curves)


# ---------------------------------------------------------------------- validation helpers


def _left_in_swing(leg: str, where: str) -> str:
    """What a goal that ends with the leg free leaves the robot in, and what puts it back."""
    return (f"the {leg} leg holds {where}, in swing: the {leg} foot stays up and the robot "
            f"stands on three feet; a Stand goal puts the foot down")


def _description() -> Go2Description:
    """The GO2 description shared by the process (its limits computed once)."""
    return Go2Description.default()


def _fail(code: int, message: str) -> NoReturn:
    raise InvalidTrajectoryError(code, message)


def _unknown_joint(field: str, name: str) -> NoReturn:
    _fail(INVALID_JOINTS, f"{field}: unknown joint {name!r}; valid joints: {_VALID_JOINTS}")


def _check_joint_names(names: tuple[str, ...]) -> tuple[np.ndarray, str]:
    """Description indices of the goal's joints, and their leg."""
    if not names:
        _fail(INVALID_GOAL, (
            "trajectory.joint_names: empty; expected 1 to 3 joints of one leg, e.g. "
            "FR_hip_joint, FR_thigh_joint, FR_calf_joint"))
    for i, name in enumerate(names):
        if name not in _LEG_OF_JOINT:
            _unknown_joint(f"trajectory.joint_names[{i}]", name)
        if name in names[:i]:
            _fail(INVALID_JOINTS, (
                f"trajectory.joint_names[{i}]: {name!r} already appears at index "
                f"{names.index(name)}; each joint may appear once"))
    legs = sorted({_LEG_OF_JOINT[name] for name in names}, key=LEGS.index)
    if len(legs) > 1:
        _fail(INVALID_GOAL, (
            f"trajectory.joint_names: joints of the legs {', '.join(legs)} received; a goal may "
            "move the joints of one leg only, because a standing robot keeps its other three "
            "feet on the ground to balance (the leg is lifted first); send one goal per leg"))
    return np.array([JOINT_NAMES.index(name) for name in names]), legs[0]


def _point_field(points: list[JointTrajectoryPoint], field: str, names: tuple[str, ...], *,
                 required: bool) -> np.ndarray | None:
    """One field of every point as an (n, k) array; ``None`` when no point gives it."""
    k = len(names)
    given = [bool(getattr(point, field)) for point in points]
    if not required and not any(given):
        return None
    first = given.index(True) if any(given) else 0
    for i, point in enumerate(points):
        values = getattr(point, field)
        if len(values) != k:
            also = "" if required else (
                f", or none in every point (points[{first}] gives {field}, so every point must)")
            _fail(INVALID_GOAL, (
                f"trajectory.points[{i}].{field}: expected {k} values (one per joint name)"
                f"{also}; received {len(values)}"))
        for j, value in enumerate(values):
            if not math.isfinite(value):
                _fail(INVALID_GOAL, (
                    f"trajectory.points[{i}].{field}[{j}] ({names[j]}): expected a finite "
                    f"number, received {value!r}"))
    return np.array([getattr(point, field) for point in points], dtype=float)


def _check_limits(values: np.ndarray, indices: np.ndarray, names: tuple[str, ...], field: str,
                  lower: np.ndarray, upper: np.ndarray, unit: str) -> None:
    low, high = lower[indices], upper[indices]
    outside = (values < low) | (values > high)
    if outside.any():
        i, j = (int(n) for n in np.argwhere(outside)[0])
        _fail(INVALID_GOAL, (
            f"trajectory.points[{i}].{field}[{j}] ({names[j]}): {values[i, j]:g} {unit} is "
            f"outside the joint's limits; valid: [{low[j]:.3f}, {high[j]:.3f}] {unit}"))


def _tolerances(entries: list[JointTolerance], field: str, names: tuple[str, ...],
                default_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity tolerances per goal joint; inf where there is no limit.

    Entries for GO2 joints the trajectory does not name are ignored.
    """
    position = np.full(len(names), default_rad)
    velocity = np.full(len(names), np.inf)
    seen: dict[str, int] = {}
    for i, entry in enumerate(entries):
        if entry.name not in _LEG_OF_JOINT:
            _unknown_joint(f"{field}[{i}].name", entry.name)
        if entry.name in seen:
            _fail(INVALID_JOINTS, (
                f"{field}[{i}].name: {entry.name!r} already has a tolerance at "
                f"{field}[{seen[entry.name]}]; give each joint at most one"))
        seen[entry.name] = i
        values = {}
        for part in ("position", "velocity", "acceleration"):
            value = getattr(entry, part)
            if not (value >= 0.0 or value == _NO_LIMIT):
                _fail(INVALID_GOAL, (
                    f"{field}[{i}].{part} ({entry.name}): expected > 0, 0 (the default) or "
                    f"-1 (no limit); received {value!r}"))
            values[part] = value
        if values["acceleration"] > 0.0:
            _fail(INVALID_GOAL, (
                f"{field}[{i}].acceleration ({entry.name}): not supported (joint accelerations "
                f"are not measured); received {values['acceleration']!r}, expected 0 or -1"))
        if entry.name in names:
            j = names.index(entry.name)
            for array, value in ((position, values["position"]), (velocity, values["velocity"])):
                if value == _NO_LIMIT:
                    array[j] = np.inf
                elif value > 0.0:
                    array[j] = value
    return position, velocity


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
