"""GO2 FollowJointTrajectory: validation codes, ROS 2 tutorial patterns, tolerances, cancel."""

from __future__ import annotations

from concurrent.futures import Future

import numpy as np
import pytest

from actions import (
    Duration,
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    GoalRejectedError,
    GoalStatus,
    Header,
    JointComponentTolerance,
    JointTolerance,
    JointTrajectory,
    JointTrajectoryPoint,
    MultiDOFJointTrajectory,
    StandGoal,
    Time,
)
from actions.go2.follow_joint_trajectory_behaviour import (
    DEFAULT_GOAL_TOLERANCE_RAD,
    DEFAULT_PATH_TOLERANCE_RAD,
    FollowJointTrajectoryBehaviour,
    JointSpline,
    plan_trajectory,
)
from actions.go2.go2_actions import FOLLOW_JOINT_TRAJECTORY_ACTION, STAND_ACTION
from actions.go2.robot_context import tilt_deg
from sim.control_loop import ControlLoop
from wbc.model.description import JOINT_NAMES

R = FollowJointTrajectoryResult
FR_JOINTS = ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"]
FR_CALF = JOINT_NAMES.index("FR_calf_joint")
VALID = ", ".join(JOINT_NAMES)


def point(positions, seconds, **fields) -> JointTrajectoryPoint:
    return JointTrajectoryPoint(positions=positions, time_from_start=seconds, **fields)


def goal(names, *points, stamp: Time | None = None, **fields) -> FollowJointTrajectoryGoal:
    trajectory = JointTrajectory(header=Header(stamp=stamp or Time()), joint_names=names,
                                 points=list(points))
    return FollowJointTrajectoryGoal(trajectory=trajectory, **fields)


def joints(loop: ControlLoop) -> np.ndarray:
    """The joint angles [rad], description order (the simulator's true state)."""
    return loop.true_state()[0][7:]


def trajectory_times(feedback) -> np.ndarray:
    """``desired.time_from_start`` [s] of each feedback message: the trajectory time reached."""
    return np.array([m.desired.time_from_start.to_seconds() for m in feedback])


#: What a goal that ends with the leg free says of the robot.
LEFT_IN_SWING = ("in swing: the FR foot stays up and the robot stands on three feet; a Stand "
                 "goal puts the foot down")


def assert_standing(loop: ControlLoop, stance: list[str]) -> None:
    """Spin a little, then: upright at standing height on the given feet, no fallback."""
    loop.spin_for(0.05)
    q, _ = loop.true_state()
    assert loop.controller.stance_legs == stance
    assert q[2] > 0.30
    assert tilt_deg(q) < 3.0
    assert loop.last_output.status.name == "OK"


# ---------------------------------------------------------------------- rejections


@pytest.fixture(scope="module")
def idle_loop() -> ControlLoop:
    loop = ControlLoop.simulated()
    loop.spin_for(0.05)
    return loop


STEP = [-0.1, 0.2, -1.6]
REJECTIONS = {
    "unknown joint": (
        goal(["FR_hip_joint", "FR_knee_joint"], point([0.0, 0.0], 1.0)), R.INVALID_JOINTS,
        f"trajectory.joint_names[1]: unknown joint 'FR_knee_joint'; valid joints: {VALID}"),
    "duplicate joint": (
        goal(["FR_calf_joint", "FR_hip_joint", "FR_calf_joint"], point(STEP, 1.0)),
        R.INVALID_JOINTS,
        ("trajectory.joint_names[2]: 'FR_calf_joint' already appears at index 0; each joint "
         "may appear once")),
    "no joints": (
        goal([], point([], 1.0)), R.INVALID_GOAL,
        ("trajectory.joint_names: empty; expected 1 to 3 joints of one leg, e.g. FR_hip_joint, "
         "FR_thigh_joint, FR_calf_joint")),
    "no points": (
        goal(FR_JOINTS), R.INVALID_GOAL,
        "trajectory.points: empty; expected at least one point"),
    "two legs": (
        goal(["FR_calf_joint", "FL_calf_joint"], point([-1.5, -1.5], 1.0)), R.INVALID_GOAL,
        ("trajectory.joint_names: joints of the legs FL, FR received; a goal may move the "
         "joints of one leg only, because a standing robot keeps its other three feet on the "
         "ground to balance (the leg is lifted first); send one goal per leg")),
    "positions length": (
        goal(FR_JOINTS, point(STEP, 1.0), point([0.0, 0.3], 2.0)), R.INVALID_GOAL,
        "trajectory.points[1].positions: expected 3 values (one per joint name); received 2"),
    "velocities in one point only": (
        goal(FR_JOINTS, point(STEP, 1.0, velocities=[0.0, 0.1, 0.0]), point(STEP, 2.0)),
        R.INVALID_GOAL,
        ("trajectory.points[1].velocities: expected 3 values (one per joint name), or none in "
         "every point (points[0] gives velocities, so every point must); received 0")),
    "accelerations length": (
        goal(FR_JOINTS, point(STEP, 1.0, velocities=[0.0] * 3, accelerations=[0.0])),
        R.INVALID_GOAL,
        ("trajectory.points[0].accelerations: expected 3 values (one per joint name), or none "
         "in every point (points[0] gives accelerations, so every point must); received 1")),
    "accelerations without velocities": (
        goal(FR_JOINTS, point(STEP, 1.0, accelerations=[0.0] * 3)), R.INVALID_GOAL,
        ("trajectory.points[0].velocities: the points give accelerations but no velocities; "
         "expected 3 velocities per point with the accelerations")),
    "first time zero": (
        goal(FR_JOINTS, point(STEP, 0.0)), R.INVALID_GOAL,
        ("trajectory.points[0].time_from_start: expected more than 0 s (the trajectory starts "
         "from the current state at time 0), received 0 s; times must increase strictly")),
    "time not increasing": (
        goal(FR_JOINTS, point(STEP, 1.5), point(STEP, 1.5)), R.INVALID_GOAL,
        ("trajectory.points[1].time_from_start: expected more than points[0].time_from_start = "
         "1.5 s, received 1.5 s; times must increase strictly")),
    "not finite": (
        goal(FR_JOINTS, point([-0.1, float("nan"), -1.6], 1.0)), R.INVALID_GOAL,
        ("trajectory.points[0].positions[1] (FR_thigh_joint): expected a finite number, "
         "received nan")),
    "outside the joint limits": (
        goal(FR_JOINTS, point(STEP, 1.0), point([-0.1, 0.2, -0.5], 2.0)), R.INVALID_GOAL,
        ("trajectory.points[1].positions[2] (FR_calf_joint): -0.5 rad is outside the joint's "
         "limits; valid: [-2.723, -0.838] rad")),
    "velocity above the limit": (
        goal(["FR_calf_joint"], point([-1.6], 1.0, velocities=[20.0])), R.INVALID_GOAL,
        ("trajectory.points[0].velocities[0] (FR_calf_joint): 20 rad/s is outside the joint's "
         "limits; valid: [-15.700, 15.700] rad/s")),
    "effort": (
        goal(["FR_calf_joint"], point([-1.6], 1.0, effort=[1.0])), R.INVALID_GOAL,
        ("trajectory.points[0].effort: not supported (the leg is position controlled); "
         "received 1 values, expected none")),
    "multi-DOF trajectory": (
        goal(FR_JOINTS, point(STEP, 1.0),
             multi_dof_trajectory=MultiDOFJointTrajectory(joint_names=["base"])),
        R.INVALID_GOAL,
        ("multi_dof_trajectory: not supported (the GO2 has no multi-DOF joints); received 1 "
         "joint names and 0 points, expected an empty one")),
    "component tolerance": (
        goal(FR_JOINTS, point(STEP, 1.0),
             component_goal_tolerance=[JointComponentTolerance(joint_name="base")]),
        R.INVALID_GOAL,
        ("component_goal_tolerance: not supported (it applies to multi-DOF joints); received 1 "
         "entries, expected none")),
    "tolerance of an unknown joint": (
        goal(FR_JOINTS, point(STEP, 1.0), path_tolerance=[JointTolerance(name="FR_foot")]),
        R.INVALID_JOINTS,
        f"path_tolerance[0].name: unknown joint 'FR_foot'; valid joints: {VALID}"),
    "two tolerances of a joint": (
        goal(FR_JOINTS, point(STEP, 1.0), goal_tolerance=[
            JointTolerance(name="FR_hip_joint", position=0.1),
            JointTolerance(name="FR_hip_joint", position=0.2)]),
        R.INVALID_JOINTS,
        ("goal_tolerance[1].name: 'FR_hip_joint' already has a tolerance at goal_tolerance[0]; "
         "give each joint at most one")),
    "negative tolerance": (
        goal(FR_JOINTS, point(STEP, 1.0),
             path_tolerance=[JointTolerance(name="FR_calf_joint", position=-0.5)]),
        R.INVALID_GOAL,
        ("path_tolerance[0].position (FR_calf_joint): expected > 0, 0 (the default) or -1 (no "
         "limit); received -0.5")),
    "acceleration tolerance": (
        goal(FR_JOINTS, point(STEP, 1.0),
             goal_tolerance=[JointTolerance(name="FR_calf_joint", acceleration=1.0)]),
        R.INVALID_GOAL,
        ("goal_tolerance[0].acceleration (FR_calf_joint): not supported (joint accelerations are "
         "not measured); received 1.0, expected 0 or -1")),
    "negative goal time tolerance": (
        goal(FR_JOINTS, point(STEP, 1.0), goal_time_tolerance=-0.5), R.INVALID_GOAL,
        "goal_time_tolerance: expected >= 0 s (0 = the default 0.5 s), received -0.5 s"),
}


@pytest.mark.parametrize("name", list(REJECTIONS))
def test_an_invalid_goal_is_rejected_with_its_error_code_naming_the_field(idle_loop, name):
    bad_goal, code, message = REJECTIONS[name]
    with pytest.raises(GoalRejectedError) as err:
        idle_loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(bad_goal)
    assert (err.value.rejection.code, err.value.rejection.message) == (code, message)
    assert_standing(idle_loop, ["FL", "FR", "RL", "RR"])


def test_a_trajectory_that_ends_before_the_robot_clock_is_an_old_header_timestamp(idle_loop):
    old = goal(FR_JOINTS, point(STEP, 0.01), stamp=Time(nanosec=2_000_000))
    with pytest.raises(GoalRejectedError) as err:
        idle_loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(old)
    now = idle_loop.runner.now_s
    assert err.value.rejection.code == R.OLD_HEADER_TIMESTAMP == -3
    assert err.value.rejection.message == (
        f"trajectory.header.stamp: 0.002 s + the last time_from_start 0.01 s = 0.012 s is "
        f"before the robot's clock ({now:g} s); expected a zero stamp (start now) or one whose "
        "trajectory ends in the future")
    assert_standing(idle_loop, ["FL", "FR", "RL", "RR"])


def test_a_goal_that_became_invalid_before_it_started_ends_aborted_with_the_code(idle_loop):
    # Checked again at start, since a goal may wait behind another one's unwind.
    behaviour = FollowJointTrajectoryBehaviour(idle_loop.context)
    now = idle_loop.runner.now_s
    behaviour.start(goal(FR_JOINTS, point(STEP, 0.01), stamp=Time(nanosec=2_000_000)), now)
    step = behaviour.step(now)
    assert step.status == GoalStatus.ABORTED
    assert step.result.error_code == R.OLD_HEADER_TIMESTAMP
    assert step.result.error_string.startswith("trajectory.header.stamp: 0.002 s + the last ")
    assert_standing(idle_loop, ["FL", "FR", "RL", "RR"])


def test_tolerances_0_take_the_default_and_minus_1_removes_the_limit():
    plan = plan_trajectory(goal(
        FR_JOINTS, point(STEP, 1.0),
        path_tolerance=[JointTolerance(name="FR_calf_joint", position=-1, velocity=0.5),
                        JointTolerance(name="FR_hip_joint", position=0.05),
                        JointTolerance(name="RL_calf_joint", position=0.3)],  # not moved: ignored
        goal_tolerance=[JointTolerance(name="FR_thigh_joint", position=0, velocity=-1)]))
    assert plan.path_tolerance.tolist() == [0.05, DEFAULT_PATH_TOLERANCE_RAD, np.inf]
    assert plan.path_velocity_tolerance.tolist() == [np.inf, np.inf, 0.5]
    assert plan.goal_tolerance.tolist() == [DEFAULT_GOAL_TOLERANCE_RAD] * 3
    assert plan.goal_velocity_tolerance.tolist() == [np.inf] * 3
    assert plan.goal_time_tolerance_s == 0.5
    assert plan.leg == "FR" and plan.joint_indices.tolist() == [3, 4, 5]


def test_a_robot_that_is_not_standing_rejects_the_goal():
    loop = ControlLoop.simulated(pose="lying")
    with pytest.raises(GoalRejectedError) as err:
        loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(
            goal(FR_JOINTS, point(STEP, 1.0)))
    assert err.value.rejection.code == R.INVALID_GOAL
    assert err.value.rejection.message.startswith("robot not standing: base tilt ")
    assert err.value.rejection.message.endswith("(at least 0.25); send a Stand goal first")


# ---------------------------------------------------------------------- interpolation


def test_the_spline_starts_at_rest_and_meets_every_point_with_its_velocity():
    start = np.array([-0.07, 0.8, -1.4])
    hermite = plan_trajectory(goal(FR_JOINTS, point([-0.1, 0.5, -1.6], 0.5, velocities=[0, -1, 0]),
                                   point([-0.1, 0.2, -1.8], 1.2, velocities=[0, 0, 0])))
    spline = JointSpline(hermite, start)
    assert np.allclose(spline.sample(0.0)[0], start)
    assert np.allclose(spline.sample(1e-9)[1], 0.0, atol=1e-6)
    assert np.allclose(spline.sample(0.5)[0], [-0.1, 0.5, -1.6])
    assert np.allclose(spline.sample(0.5 - 1e-9)[1], [0, -1, 0], atol=1e-6)
    assert np.allclose(spline.sample(5.0)[0], [-0.1, 0.2, -1.8])
    positions_only = plan_trajectory(goal(["FR_calf_joint"], point([-1.8], 2.0)))
    p, v, a = JointSpline(positions_only, np.array([-1.4])).sample(1.0)
    # One point, positions only: the minimum-jerk profile (peak speed 1.875 * distance / T).
    assert np.allclose([p[0], v[0], a[0]], [-1.6, -1.875 * 0.4 / 2.0, 0.0])


# ---------------------------------------------------------------------- in MuJoCo


def test_tutorial_one_point_for_a_leg_reached_in_3_s_with_send_goal_and_wait():
    loop = ControlLoop.simulated()
    target = [-0.1, -0.3, -1.6]  # foot raised about 0.2 m, in front of the shoulder
    feedback = []
    wrapped = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(
        goal(FR_JOINTS, point(target, Duration(sec=3))), feedback_callback=feedback.append)
    assert wrapped.status == GoalStatus.SUCCEEDED
    assert wrapped.result == R(error_code=R.SUCCESSFUL, error_string=(
        f"goal reached: the FR leg holds the last point, {LEFT_IN_SWING}"))
    assert np.all(np.abs(joints(loop)[3:6] - target) < DEFAULT_GOAL_TOLERANCE_RAD)
    messages = [m.feedback for m in feedback]
    assert {m.header.frame_id for m in messages} == {""}  # as control_msgs: no phase there
    assert all(m.joint_names == FR_JOINTS for m in messages)
    stamps = np.array([m.header.stamp.to_seconds() for m in messages])
    assert np.diff(stamps).max() <= 0.02 + 1e-6  # 50 Hz
    times = trajectory_times(messages)
    assert np.all(np.diff(times) >= 0.0)  # the trajectory time never goes back
    # 0 while the leg is released (shift 1.0 s + unload 0.4 s), then the clock's time.
    first = int(np.argmax(times > 0.0))
    assert 1.3 < stamps[first] - times[first] < 1.5
    np.testing.assert_allclose(stamps[first:] - times[first:], stamps[first] - times[first],
                               atol=1e-6)
    following = [m for m, t in zip(messages, times) if 0.0 < t <= 3.0]
    assert following[-1].desired.time_from_start.to_seconds() == pytest.approx(3.0, abs=0.021)
    assert times[-1] > 3.0  # success is judged after the last point's time
    tracking = max(np.abs(m.error.positions).max() for m in following)
    assert tracking < 0.01
    q, _ = loop.true_state()
    assert q[2] > 0.25 and tilt_deg(q) < 3.0
    loop.spin_for(0.5)  # the leg holds its target, in swing, on three feet
    assert np.all(np.abs(joints(loop)[3:6] - target) < DEFAULT_GOAL_TOLERANCE_RAD)
    assert_standing(loop, ["FL", "RL", "RR"])


def test_tutorial_one_joint_async_with_feedback_and_result_callbacks():
    loop = ControlLoop.simulated()
    client = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION)
    feedback, results = [], []

    def get_result_callback(future: Future) -> None:
        results.append(future.result())

    def goal_response_callback(future: Future) -> None:
        goal_handle = future.result()
        assert goal_handle.accepted
        goal_handle.get_result_async().add_done_callback(get_result_callback)

    request = goal(["FR_calf_joint"], point([-1.9], Duration(sec=1)),
                   goal_time_tolerance=Duration(sec=1))
    future = client.send_goal_async(request, feedback_callback=lambda m: feedback.append(m))
    future.add_done_callback(goal_response_callback)
    while not results and loop.robot.time_s < 5.0:
        loop.spin_once()
    assert results[0].status == GoalStatus.SUCCEEDED
    assert results[0].result.error_code == R.SUCCESSFUL
    assert abs(joints(loop)[FR_CALF] + 1.9) < DEFAULT_GOAL_TOLERANCE_RAD
    last = [m.feedback for m in feedback
            if 0.0 < m.feedback.desired.time_from_start.to_seconds() <= 1.0][-1]
    assert last.joint_names == ["FR_calf_joint"]
    assert last.desired.positions[0] == pytest.approx(-1.9, abs=1e-3)
    assert last.error.positions[0] == pytest.approx(
        last.desired.positions[0] - last.actual.positions[0])
    assert last.error.velocities[0] == pytest.approx(
        last.desired.velocities[0] - last.actual.velocities[0])
    assert_standing(loop, ["FL", "RL", "RR"])


def test_a_later_goal_for_the_swinging_leg_starts_at_once_and_stand_puts_the_foot_down():
    loop = ControlLoop.simulated()
    client = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION)
    assert client.send_goal_and_wait(goal(FR_JOINTS, point(STEP, 1.0))).result.error_code == 0
    with pytest.raises(GoalRejectedError) as err:  # one foot off the ground at a time
        client.send_goal_and_wait(goal(["FL_calf_joint"], point([-1.6], 1.0)))
    assert err.value.rejection.code == R.INVALID_GOAL
    assert err.value.rejection.message == (
        "trajectory.joint_names: cannot move the FL leg while FR is in swing (at most one foot "
        "may be off the ground); send a Stand goal to put it down first, or a trajectory for FR")
    feedback = []
    again = client.send_goal_and_wait(goal(["FR_thigh_joint"], point([0.5], 0.5)),
                                      feedback_callback=feedback.append)
    assert again.result.error_code == R.SUCCESSFUL
    times = trajectory_times([m.feedback for m in feedback])
    assert times[0] == 0.0 and 0.0 < times[1] <= 0.021  # no release this time
    stand = loop.client(STAND_ACTION).send_goal_and_wait(StandGoal(duration_s=1.0))
    assert stand.status == GoalStatus.SUCCEEDED
    loop.spin_for(0.2)
    assert loop.last_output.forces[1, 2] > 30.0  # FR carries weight again
    assert_standing(loop, ["FL", "FR", "RL", "RR"])


def test_a_fast_motion_with_a_tight_path_tolerance_aborts_and_holds():
    loop = ControlLoop.simulated()
    request = goal(["FR_calf_joint"], point([-1.9], 0.3),
                   path_tolerance=[JointTolerance(name="FR_calf_joint", position=0.001)])
    wrapped = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(request)
    assert wrapped.status == GoalStatus.ABORTED
    assert wrapped.result.error_code == R.PATH_TOLERANCE_VIOLATED
    message = wrapped.result.error_string
    assert message.startswith("path tolerance violated at t=")
    assert "s of the trajectory: FR_calf_joint position error " in message
    assert message.endswith(
        "rad exceeds its tolerance 0.001 rad (path_tolerance; 0 = the default 0.1 rad, -1 = no "
        f"limit); the FR leg holds where it was, {LEFT_IN_SWING}")
    stopped = joints(loop)[FR_CALF]
    loop.spin_for(0.5)
    assert abs(joints(loop)[FR_CALF] - stopped) < 0.02
    assert_standing(loop, ["FL", "RL", "RR"])


def test_a_goal_tolerance_not_met_in_the_goal_time_aborts():
    loop = ControlLoop.simulated()
    # 1 urad, 20 ms after a 1 s move: no controller settles that close that fast.
    request = goal(["FR_calf_joint"], point([-1.9], 1.0), goal_time_tolerance=0.02,
                   goal_tolerance=[JointTolerance(name="FR_calf_joint", position=1e-6)])
    feedback = []
    wrapped = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION).send_goal_and_wait(
        request, feedback_callback=feedback.append)
    assert wrapped.status == GoalStatus.ABORTED
    assert wrapped.result.error_code == R.GOAL_TOLERANCE_VIOLATED
    message = wrapped.result.error_string
    assert message.startswith("goal tolerance violated 0.02")
    assert "s after the last point's time (goal_time_tolerance 0.02 s): FR_calf_joint " in message
    assert "exceeds its tolerance 1e-06 rad (goal_tolerance; 0 = the default 0.02 rad" in message
    assert trajectory_times([m.feedback for m in feedback]).max() > 1.0  # past the last point
    assert_standing(loop, ["FL", "RL", "RR"])


def test_cancel_mid_trajectory_holds_the_leg_and_ends_canceled():
    loop = ControlLoop.simulated()
    client = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION)
    feedback = []
    # A stamp 1.6 s ahead: the leg is free after 1.4 s, then waits for the stamp.
    request = goal(["FR_calf_joint"], point([-2.3], 2.0), stamp=Time.from_seconds(1.6))
    handle_future = client.send_goal_async(request, feedback_callback=feedback.append)
    while not feedback or feedback[-1].feedback.desired.time_from_start.to_seconds() < 0.8:
        loop.spin_once()
    at_cancel = joints(loop)[FR_CALF]
    handle = handle_future.result()
    handle.cancel_goal_async()
    result_future = handle.get_result_async()
    loop.spin_once()
    loop.spin_once()
    assert result_future.done()
    wrapped = result_future.result()
    assert wrapped.status == GoalStatus.CANCELED
    assert wrapped.result.error_code == R.SUCCESSFUL
    assert wrapped.result.error_string.startswith(
        "canceled (canceled by client request) at t=0.8")
    assert wrapped.result.error_string.endswith(
        f"of the trajectory: the FR leg holds where it was, {LEFT_IN_SWING}")
    times = trajectory_times([m.feedback for m in feedback])
    stamps = np.array([m.feedback.header.stamp.to_seconds() for m in feedback])
    # 0 while the leg is released and until the stamp, then the clock's time from the stamp.
    first = int(np.argmax(times > 0.0))
    assert 1.6 - 1e-6 < stamps[first] < 1.6 + 0.021
    np.testing.assert_allclose(stamps[first:] - times[first:], 1.6, atol=0.002)
    loop.spin_for(0.5)
    assert abs(joints(loop)[FR_CALF] - at_cancel) < 0.05  # stopped near where it was
    assert abs(loop.true_state()[1][6 + FR_CALF]) < 0.05
    assert_standing(loop, ["FL", "RL", "RR"])


def test_cancel_while_the_leg_is_released_puts_it_back_on_four_feet():
    loop = ControlLoop.simulated()
    client = loop.client(FOLLOW_JOINT_TRAJECTORY_ACTION)
    handle_future = client.send_goal_async(goal(FR_JOINTS, point(STEP, 1.0)))
    loop.spin_for(1.2)  # unloading
    handle = handle_future.result()
    handle.cancel_goal_async()
    while not handle.get_result_async().done() and loop.robot.time_s < 4.0:
        loop.spin_once()
    wrapped = handle.get_result_async().result()
    assert wrapped.status == GoalStatus.CANCELED
    assert wrapped.result.error_string == (
        "canceled (canceled by client request) while the FR leg was being released: the foot "
        "is loaded again, four feet in stance")
    assert loop.controller.support_legs() == ["FL", "FR", "RL", "RR"]
    assert_standing(loop, ["FL", "FR", "RL", "RR"])
