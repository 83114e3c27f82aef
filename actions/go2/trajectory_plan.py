"""A FollowJointTrajectory goal checked and turned into arrays: the plan the GO2's server runs.

:func:`plan_trajectory` checks what the goal says (joints of one leg, increasing times, limits,
tolerances); :func:`check_robot` checks what depends on the robot and the moment (the stamp,
that the leg can move). Each failure is an :class:`InvalidTrajectoryError` with the
FollowJointTrajectory error code and a message naming the field, the value received and what
is valid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NoReturn

import numpy as np

from actions.go2.robot_context import STANDING_HEIGHT_M, RobotContext
from actions.ros_interfaces.control_msgs import (
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    JointTolerance,
)
from actions.ros_interfaces.trajectory_msgs import JointTrajectoryPoint
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS, Go2Description

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
    stance = controller.schedule.stance_legs
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



# ---------------------------------------------------------------------- validation helpers


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
