"""Property-based tests: goals, controller parameters, CLI arguments, joint orders, conventions."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from actions import (
    FollowJointTrajectoryGoal,
    FollowJointTrajectoryResult,
    GoalStatus,
    HighFiveGoal,
    JointTrajectory,
    JointTrajectoryPoint,
)
from actions.go2.high_five_behaviour import INVALID_HOLD_SECONDS, INVALID_TARGET_HEIGHT, MAX_HOLD_S
from actions.go2.robot_context import tilt_deg
from actions.robot.robot_interface import MappedRobot
from sim import cli
from sim.control_loop import ControlLoop
from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from wbc.controller.controller_config import PATHS, ControllerConfig, ShapingSettings
from wbc.core.conventions import mujoco_to_pin, pin_to_mujoco, reorder_quaternion
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS, Go2Description
from wbc.model.joint_map import JointMap
from wbc.motions.leg_lift import MAX_HEIGHT_M, MIN_HEIGHT_M
from wbc.robot_io.motor_command import MotorCommand

#: Derandomized (the same examples every run) and without an example database on disk.
SETTINGS = settings(max_examples=50, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

#: Integers up to far beyond the float range (1.8e308).
big_ints = st.integers(min_value=-10**400, max_value=10**400)
any_floats = st.floats(allow_nan=True, allow_infinity=True)
numbers = st.one_of(any_floats, big_ints)


@pytest.fixture(scope="module")
def loop() -> ControlLoop:
    """One standing robot shared by the goal properties (each example leaves it standing)."""
    loop = ControlLoop.simulated()
    loop.spin_for(0.3)
    return loop


def four_feet_standing(loop: ControlLoop) -> bool:
    forces = loop.sim.foot_contact_forces()
    q, _ = loop.true_state()
    return (len(loop.controller.stance_legs) == 4 and q[2] > 0.25 and tilt_deg(q) < 5.0
            and all(forces[leg][2] > 5.0 for leg in LEGS))


def beyond_float(value) -> bool:
    """An int too large for a float (beyond about 1.8e308)."""
    try:
        float(value)
    except OverflowError:
        return True
    return False


def send(loop: ControlLoop, action: str, goal):
    """Send ``goal``; return its handle once accepted or rejected (one tick)."""
    future = loop.client(action).send_goal_async(goal)
    loop.spin_once()
    assert future.done()
    return future.result()


def cancel_and_unwind(loop: ControlLoop, handle) -> None:
    """Cancel an accepted goal at once and spin until it ends on four feet."""
    handle.cancel_goal_async()
    result = handle.get_result_async()
    end = loop.sim.time_s + 3.0
    while not result.done() and loop.sim.time_s < end:
        loop.spin_once()
    assert result.done() and result.result().status is GoalStatus.CANCELED
    assert loop.runner.active_goal_id is None


# ---------------------------------------------------------------------------- HighFive goals


@SETTINGS
@given(height=st.booleans().flatmap(
    lambda inside: st.floats(MIN_HEIGHT_M, MAX_HEIGHT_M) if inside else numbers),
       hold=st.one_of(st.integers(0, MAX_HOLD_S), big_ints, big_ints, any_floats))
def test_high_five_goal_is_accepted_iff_in_range(loop, height, hold):
    if isinstance(height, int) and beyond_float(height):
        event("target_height beyond the float range")
        with pytest.raises(ConfigurationError, match=r"^HighFiveGoal\.target_height must be a "
                                                     r"real number within the float range"):
            HighFiveGoal(target_height=height, hold_seconds=0)
        return
    if isinstance(hold, float):  # a message field of type int
        event("hold_seconds not an int")
        with pytest.raises(ConfigurationError, match=r"^HighFiveGoal\.hold_seconds must be an "
                                                     r"integer; received "):
            HighFiveGoal(target_height=height, hold_seconds=hold)
        return
    handle = send(loop, "high_five", HighFiveGoal(target_height=height, hold_seconds=hold))
    event("accepted" if handle.accepted else f"rejected {handle.rejection.code}")
    height_ok = math.isfinite(height) and MIN_HEIGHT_M <= height <= MAX_HEIGHT_M
    if height_ok and 0 <= hold <= MAX_HOLD_S:
        assert handle.accepted, handle.rejection
        cancel_and_unwind(loop, handle)
    else:
        assert not handle.accepted
        code, field = ((INVALID_TARGET_HEIGHT, "target_height") if not height_ok
                       else (INVALID_HOLD_SECONDS, "hold_seconds"))
        assert handle.rejection.code == code
        received = float(height) if not height_ok else hold
        assert handle.rejection.message.startswith(f"{field}: expected ")
        assert handle.rejection.message.endswith(f"received {received!r}")
    loop.spin_for(0.01)
    assert four_feet_standing(loop)


# ---------------------------------------------------------------------------- FollowJointTrajectory

INVALID_GOAL = FollowJointTrajectoryResult.INVALID_GOAL
INVALID_JOINTS = FollowJointTrajectoryResult.INVALID_JOINTS
_DESCRIPTION = Go2Description()
_LOW, _HIGH = _DESCRIPTION.position_lower, _DESCRIPTION.position_upper
FOREIGN_NAMES = ("FR_knee_joint", "", "fr_hip_joint", "FR_hip", "base")


@st.composite
def trajectory_goals(draw):
    """A FollowJointTrajectory goal: names of one leg, of two legs or anything; positions
    inside the joint limits or anything; times increasing or anything; lengths mostly right."""
    if draw(st.sampled_from([True, True, False])):  # joints of one leg, or of two
        legs = draw(st.lists(st.sampled_from(LEGS), min_size=1, max_size=1 + draw(
            st.sampled_from([0, 1])), unique=True))
        names = []
        for leg in legs:
            joints = [f"{leg}_{part}_joint" for part in ("hip", "thigh", "calf")]
            names += draw(st.lists(st.sampled_from(joints), min_size=1, max_size=3, unique=True))
        names = draw(st.permutations(names))
    else:
        names = draw(st.lists(st.sampled_from(JOINT_NAMES + FOREIGN_NAMES), max_size=4))
        event("any names")
    n_points = draw(st.sampled_from([1, 2, 3, 1, 2, 0]))
    if draw(st.sampled_from([True, True, True, False])):
        steps = draw(st.lists(st.floats(0.05, 2.0), min_size=n_points, max_size=n_points))
        times = list(np.cumsum(steps))
    else:
        times = draw(st.lists(st.floats(-1.0, 3.0), min_size=n_points, max_size=n_points))
    inside = draw(st.sampled_from([True, True, False]))
    wrong_length = draw(st.sampled_from([None, None, None, *range(n_points)]))
    points = []
    for p, t in enumerate(times):
        k = len(names) + (draw(st.sampled_from([-1, 1])) if p == wrong_length else 0)
        values = []
        for j in range(max(k, 0)):
            name = names[j] if j < len(names) else "FR_hip_joint"
            i = JOINT_NAMES.index(name) if name in JOINT_NAMES else 0
            values.append(draw(st.floats(_LOW[i], _HIGH[i]) if inside else any_floats))
        points.append(JointTrajectoryPoint(positions=values, time_from_start=float(t)))
    return FollowJointTrajectoryGoal(trajectory=JointTrajectory(joint_names=names, points=points))


def expected_rejection(goal: FollowJointTrajectoryGoal) -> int | None:
    """The code a goal must be rejected with (None: it must be accepted), judged independently."""
    names = goal.trajectory.joint_names
    if not names:
        return INVALID_GOAL
    if any(name not in JOINT_NAMES for name in names) or len(set(names)) < len(names):
        return INVALID_JOINTS
    if len({name.split("_")[0] for name in names}) > 1:
        return INVALID_GOAL
    points = goal.trajectory.points
    times = [p.time_from_start.to_seconds() for p in points]
    if not points or any(b <= a for a, b in zip([0.0, *times], times)):
        return INVALID_GOAL
    for point in points:
        if len(point.positions) != len(names):
            return INVALID_GOAL
        for name, value in zip(names, point.positions):
            i = JOINT_NAMES.index(name)
            if not _LOW[i] <= value <= _HIGH[i]:  # NaN included
                return INVALID_GOAL
    return None


@SETTINGS
@given(goal=trajectory_goals())
def test_follow_joint_trajectory_goal_is_accepted_or_rejected_with_its_code(loop, goal):
    handle = send(loop, "follow_joint_trajectory", goal)  # no exception escapes
    event("accepted" if handle.accepted else f"rejected {handle.rejection.code}")
    expected = expected_rejection(goal)
    if expected is None:
        assert handle.accepted, handle.rejection
        cancel_and_unwind(loop, handle)
    else:
        assert not handle.accepted
        assert handle.rejection.code == expected, handle.rejection.message
        message = handle.rejection.message
        assert "\n" not in message and message.split(":")[0].split("[")[0].split(".")[0] in (
            "trajectory", "goal_time_tolerance")
    assert loop.controller.stance_legs == list(LEGS)
    loop.spin_for(0.01)
    assert four_feet_standing(loop)


# ---------------------------------------------------------------------------- controller parameters

CONFIG_FIELDS = [path.split(".")[1] for path in PATHS]
_DEFAULTS = ControllerConfig()


def config_value_is_valid(name: str, value) -> bool:
    """The documented ranges of ControllerConfig, with the other fields at their defaults."""
    if name == "backend":
        return isinstance(value, str) and value != ""
    if name in ShapingSettings.PER_JOINT_TYPE:  # (hip, thigh, calf), each in [0, 10]
        return (isinstance(value, tuple) and len(value) == 3
                and all(math.isfinite(v) and 0.0 <= v <= 10.0 for v in value))
    if isinstance(value, tuple):
        return False
    if isinstance(value, bool) or not isinstance(value, int | float) or beyond_float(value):
        return False
    if not math.isfinite(value):
        return False
    strictly_positive = {"control_period_s", "max_normal_force_n", "joint_limit_horizon_s",
                         "support_omega", "torque_limit_fraction", "friction_coefficient",
                         "friction_velocity_scale_rad_s"}
    if value < 0.0 or (value == 0.0 and name in strictly_positive):
        return False
    return {"torque_limit_fraction": value <= 1.0, "friction_coefficient": value <= 5.0,
            "control_period_s": 1e-4 <= value <= 0.01,
            "stance_kp": value <= 500.0, "swing_kp": value <= 500.0,
            "stance_kd": value <= 50.0, "swing_kd": value <= 50.0,
            "min_normal_force_n": value < _DEFAULTS.contacts.max_normal_force_n,
            "max_normal_force_n": value > _DEFAULTS.contacts.min_normal_force_n}.get(name, True)


@SETTINGS
@given(name=st.sampled_from(CONFIG_FIELDS),
       value=st.one_of(numbers, st.booleans(), st.none(), st.text(max_size=5),
                       st.floats(0.0, 1.0), st.floats(0.0, 1e3),
                       st.tuples(st.floats(-1.0, 12.0), st.floats(0.0, 1.0), st.floats(0.0, 2.0))))
def test_controller_config_field_is_valid_or_a_configuration_error_naming_it(name, value):
    part = ControllerConfig.path_of(name).split(".")[0]
    try:
        config = ControllerConfig(**{part: {name: value}})
        event("valid")
    except ConfigurationError as err:  # any other exception type fails the test
        event("ConfigurationError")
        assert not config_value_is_valid(name, value)
        assert str(err).startswith(f"{name}:") or f" {name} " in str(err), str(err)
        return
    assert config_value_is_valid(name, value)
    assert getattr(getattr(config, part), name) == value


# ---------------------------------------------------------------------------- CLI arguments


def number_text(low: float, high: float):
    """Text of a number in ``[low, high]`` (3 times in 4), else near it, or not a number."""
    other = st.one_of(st.floats(low - 1.0, high + 1.0).map(lambda x: f"{x:.3f}"),
                      st.integers(int(low) - 2, int(high) + 2).map(str), numbers.map(str),
                      st.text(alphabet="0123456789.-+eEinfa x_,", min_size=1, max_size=8))
    inside = st.floats(low, high).map(str)
    return st.integers(0, 3).flatmap(lambda i: inside if i else other)


def as_float(text: str) -> float | None:
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def as_int(text: str) -> int | None:
    try:
        return int(text)
    except ValueError:
        return None


class _Parsed(Exception):
    """Raised by the patched GoalRun.run: parsing ended and the goal was built."""


def run_cli(argv: list[str]) -> tuple[int | str, str]:
    """``main(argv)`` without a simulation: the exit code (or 'run') and stderr."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = cli.main(argv)
        except SystemExit as exit_:
            code = exit_.code
        except _Parsed:
            code = "run"
    return code, err.getvalue()


@pytest.fixture(scope="module")
def goal_runs():
    """GoalRun.run replaced: records the goal it would send, raises _Parsed."""
    runs = []

    def run(self):
        runs.append((self.action_name, self.goal, self.args))
        raise _Parsed

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(cli.GoalRun, "run", run)
        yield runs


def usage_error_names(code, stderr: str, option: str) -> None:
    event(f"usage error {option.split(':')[0]}")
    assert code == cli.EXIT_USAGE, (code, stderr)
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith("go2-wbc high-five: error: ") and option in lines[0], lines[0]


@settings(SETTINGS, max_examples=200)
@given(height=number_text(MIN_HEIGHT_M, MAX_HEIGHT_M), hold=st.integers(0, 3).flatmap(
    lambda i: st.integers(0, MAX_HOLD_S).map(str) if i else number_text(0, MAX_HOLD_S)),
       push=st.one_of(st.none(), st.tuples(number_text(0, 500), number_text(0, 5)).map(
           ",".join), number_text(0, 500)),
       direction=st.one_of(st.none(), number_text(-360, 360)))
def test_cli_high_five_options_are_valid_or_a_one_line_usage_error(goal_runs, height, hold,
                                                                    push, direction):
    argv = ["high-five", f"--height={height}", f"--hold={hold}"]
    if push is not None:
        argv.append(f"--push={push}")
    if direction is not None:
        argv.append(f"--push-dir={direction}")
    goal_runs.clear()
    code, stderr = run_cli(argv)
    h, s = as_float(height), as_int(hold)
    if h is None or not MIN_HEIGHT_M <= h <= MAX_HEIGHT_M:
        return usage_error_names(code, stderr, "--height")
    if s is None or not 0 <= s <= MAX_HOLD_S:
        return usage_error_names(code, stderr, "--hold")
    if push is not None:
        parts = [as_float(p) for p in push.split(",")]
        if len(parts) != 2 or None in parts or not (0 <= parts[0] <= 500 and 0 < parts[1] <= 5):
            return usage_error_names(code, stderr, "--push")
    if direction is not None:
        d = as_float(direction)
        if d is None or not -360 <= d <= 360:
            return usage_error_names(code, stderr, "--push-dir")
        if push is None:
            return usage_error_names(code, stderr, "--push-dir: only used with --push")
    assert code == "run", stderr
    event("valid")
    (action, goal, args), = goal_runs
    assert action == "high_five" and goal == HighFiveGoal(target_height=h, hold_seconds=s)
    assert args.push_dir == (90.0 if direction is None else float(direction))


TRAJECTORY_KEYS = ("joint_names", "points", "path_tolerance", "goal_tolerance",
                   "goal_time_tolerance", "positions", "velocities", "time_from_start", "name",
                   "position", "sec", "nanosec", "effort", "other")
json_scalars = st.one_of(st.none(), st.booleans(), big_ints, st.floats(allow_nan=False),
                        st.text(max_size=6), st.sampled_from(JOINT_NAMES))
json_values = st.recursive(json_scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4),
    st.dictionaries(st.sampled_from(TRAJECTORY_KEYS), inner, max_size=4)), max_leaves=12)


@st.composite
def trajectory_files(draw):
    """A JSON trajectory file's content: a valid one, changed in one place, or anything."""
    point = {"positions": [-0.1, -0.3, -1.6], "time_from_start": 2.0}
    data = {"joint_names": ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"],
            "points": [point], "goal_tolerance": [{"name": "FR_calf_joint", "position": 0.05}]}
    change = draw(st.one_of(*map(st.just, ("file", "point", "all", "nothing"))))
    event(f"change {change}")
    if change == "all":
        return draw(json_values)
    if change != "nothing":
        where = data if change == "file" else point
        where[draw(st.sampled_from(TRAJECTORY_KEYS))] = draw(json_values)
    return data


@SETTINGS
@given(content=trajectory_files())
def test_cli_trajectory_file_is_a_goal_or_a_one_line_usage_error(goal_runs, tmp_path_factory,
                                                                 content):
    path = tmp_path_factory.getbasetemp() / "trajectory.json"
    path.write_text(json.dumps(content))
    goal_runs.clear()
    code, stderr = run_cli(["trajectory", str(path)])
    if code == "run":
        event("valid")
        (action, goal, _), = goal_runs
        assert action == "follow_joint_trajectory"
        assert goal.trajectory.joint_names == content["joint_names"]
        return
    event("usage error")
    assert code == cli.EXIT_USAGE, stderr
    lines = stderr.splitlines()
    assert len(lines) == 1, stderr
    assert lines[0].startswith(f"go2-wbc trajectory: error: FILE: {str(path)!r} is not a valid "
                               "trajectory file: "), lines[0]


def test_cli_trajectory_file_with_a_number_as_a_key(tmp_path):
    path = tmp_path / "trajectory.yaml"
    path.write_text("{1: a, other: b, joint_names: [FR_hip_joint], points: []}\n")
    code, stderr = run_cli(["trajectory", str(path)])
    assert code == cli.EXIT_USAGE
    assert "is not a valid trajectory file: file: unknown key" in stderr, stderr


# ---------------------------------------------------------------------------- joint orders


permutations = st.permutations(JOINT_NAMES)
joint_values = st.lists(st.floats(-1e6, 1e6), min_size=12, max_size=12).map(np.array)


@settings(max_examples=100, deadline=None, derandomize=True, database=None)
@given(order=permutations, values=joint_values)
def test_joint_map_round_trips_and_maps_by_name(order, values):
    joint_map = JointMap(order)
    other = joint_map.to_other(values)
    np.testing.assert_array_equal(joint_map.from_other(other), values)
    for i, name in enumerate(order):
        assert other[i] == values[JOINT_NAMES.index(name)]


unit_quaternions = st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda x: np.linalg.norm(x) > 0.1).map(lambda x: np.array(x) / np.linalg.norm(x))


@settings(max_examples=100, deadline=None, derandomize=True, database=None)
@given(quaternion=unit_quaternions, position=st.lists(st.floats(-10, 10), min_size=3, max_size=3),
       joints=st.lists(st.floats(-3, 3), min_size=12, max_size=12),
       v=st.lists(st.floats(-10, 10), min_size=18, max_size=18))
def test_pinocchio_mujoco_state_conversion_round_trips(quaternion, position, joints, v):
    q = np.concatenate([position, quaternion, joints])
    v = np.array(v)
    qpos, qvel = pin_to_mujoco(q, v)
    np.testing.assert_array_equal(qpos[3:7], reorder_quaternion(quaternion, to="wxyz"))
    np.testing.assert_array_equal(reorder_quaternion(qpos[3:7], to="xyzw"), quaternion)
    np.testing.assert_allclose(np.linalg.norm(qvel[:3]), np.linalg.norm(v[:3]), atol=1e-9)
    q2, v2 = mujoco_to_pin(qpos, qvel)
    np.testing.assert_allclose(q2, q, atol=1e-12)
    np.testing.assert_allclose(v2, v, atol=1e-9)


@settings(max_examples=15, deadline=None, derandomize=True, database=None)
@given(order=permutations, tau=st.lists(st.floats(-20, 20), min_size=12, max_size=12))
def test_a_plant_in_any_actuator_order_is_seen_in_the_description_order(order, tau):
    sim = Go2Simulator(actuator_order=order)
    robot = MappedRobot(MujocoRobot(sim))
    q, v = robot.read_state()
    q_sim, v_sim = sim.state()
    np.testing.assert_array_equal(q, q_sim)
    np.testing.assert_array_equal(v, v_sim)
    robot.write_command(MotorCommand.pure_torque(np.array(tau)))  # one step with these torques
    for i in range(sim.model.nu):
        joint = sim.model.joint(sim.model.actuator_trnid[i, 0]).name
        assert sim.model.actuator(i).name == joint.removesuffix("_joint")
        assert sim.data.ctrl[i] == pytest.approx(tau[JOINT_NAMES.index(joint)])
        assert sim.data.actuator_force[i] == pytest.approx(tau[JOINT_NAMES.index(joint)])


# ---------------------------------------------------------------------------- huge integers


def test_controller_config_with_an_int_too_large_for_a_float():
    with pytest.raises(ConfigurationError, match="^com_kp: "):
        ControllerConfig(gains={"com_kp": 10**400})


def test_high_five_goal_with_an_int_too_large_for_a_float():
    with pytest.raises(ConfigurationError, match="^HighFiveGoal.target_height"):
        HighFiveGoal(target_height=10**400, hold_seconds=1)
