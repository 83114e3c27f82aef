"""The gait's parts without a simulator: parameters, the clock's phases, swing paths, footholds."""

import math

import numpy as np
import pytest

from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.locomotion import (
    FootholdPlanner,
    GaitClock,
    GaitParameters,
    VelocityLimits,
    swing_reference,
)


def test_default_gait_is_a_trot_with_double_support():
    gait = GaitParameters()
    assert gait.name == "trot"
    assert gait.offsets == (0.0, 0.5, 0.5, 0.0)  # FL with RR, FR with RL
    assert gait.duty_factor == 0.55
    assert gait.stance_s == pytest.approx(0.275) and gait.swing_s == pytest.approx(0.225)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"period_s": 0.1}, r"period_s: expected a value in \[0.2, 2\], received 0.1"),
    ({"duty_factor": 0.5}, r"duty_factor: expected a value in \(0.5, 0.9\], received 0.5"),
    ({"duty_factor": 0.95}, r"duty_factor: expected a value in \(0.5, 0.9\], received 0.95"),
    ({"name": "walk", "duty_factor": 0.7},
     r"duty_factor: expected a value in \[0.75, 0.9\], received 0.7"),
    ({"swing_height_m": 0.5}, r"swing_height_m: expected a value in \[0.02, 0.2\], received 0.5"),
    ({"transfer_s": 0.2}, r"transfer_s: expected at most half the stance time \(0.1375 s"),
    ({"period_s": "fast"}, r"period_s: expected a number, received 'fast'"),
])
def test_gait_parameters_are_checked(kwargs, message):
    with pytest.raises(ConfigurationError, match=message):
        GaitParameters(**kwargs)


def test_unknown_gait_lists_the_gaits():
    with pytest.raises(UnknownNameError, match="unknown gait 'gallop'; valid gaits: trot, walk"):
        GaitParameters(name="gallop")


def test_velocity_limits_name_the_field_value_and_range():
    limits = VelocityLimits(forward_mps=1.0, lateral_mps=0.4, yaw_rate_radps=1.2)
    assert limits.check(0.5, -0.4, 1) == (0.5, -0.4, 1.0)
    with pytest.raises(ConfigurationError,
                       match=r"forward_mps: expected a velocity in \[-1, 1\] m/s, received 1.5"):
        limits.check(1.5, 0.0, 0.0)
    with pytest.raises(ConfigurationError, match=(
            r"yaw_rate_radps: expected a velocity in \[-1.2, 1.2\] rad/s, received -2.0")):
        limits.check(0.0, 0.0, -2.0)
    with pytest.raises(ConfigurationError, match=(
            r"lateral_mps: expected a velocity in \[-0.4, 0.4\] m/s, received nan")):
        limits.check(0.0, math.nan, 0.0)
    with pytest.raises(ConfigurationError,
                       match=r"lateral_mps: expected a value in \[0, 1\], received -0.1"):
        VelocityLimits(lateral_mps=-0.1)


def test_trot_clock_moves_diagonal_pairs_in_antiphase():
    gait = GaitParameters(period_s=0.5, duty_factor=0.6)
    clock = GaitClock(gait)
    times = np.arange(0.0, 2.0, 0.001)
    swing = np.array([[clock.in_swing(leg, t) for leg in ("FL", "FR", "RL", "RR")]
                      for t in times])
    assert (swing[:, 0] == swing[:, 3]).all() and (swing[:, 1] == swing[:, 2]).all()
    assert not (swing[:, 0] & swing[:, 1]).any()  # never both pairs in the air
    # Each foot swings 40 % of the time; all four stand 20 % (two 0.05 s exchanges a cycle).
    assert swing[:, 0].mean() == pytest.approx(0.4, abs=2e-3)
    assert (~swing.any(axis=1)).mean() == pytest.approx(0.2, abs=2e-3)


def test_clock_phases_times_and_cycle_numbers():
    clock = GaitClock(GaitParameters(period_s=0.5, duty_factor=0.6))
    # FR's cycle starts at 0.25 s (offset 0.5): at 0.3 s it is 0.1 into its stance.
    assert clock.cycle("FR", 0.3) == (0, pytest.approx(0.1))
    assert clock.cycle("FR", 0.2) == (-1, pytest.approx(0.9))
    assert clock.time_to_liftoff("FR", 0.3) == pytest.approx(0.25)
    assert clock.time_to_touchdown("FR", 0.3) == pytest.approx(0.45)
    assert clock.time_to_liftoff("FL", 0.35) == 0.0  # in the air
    assert clock.swing_progress("FL", 0.40) == pytest.approx(0.5)
    assert clock.swing_progress("FL", 0.1) == 0.0


def test_walk_gait_lifts_one_foot_at_a_time():
    clock = GaitClock(GaitParameters(name="walk", period_s=1.0, duty_factor=0.8))
    for t in np.arange(0.0, 2.0, 0.001):
        assert sum(clock.in_swing(leg, t) for leg in ("FL", "FR", "RL", "RR")) <= 1


def _path(progress, start, end, duration=0.2, height=0.08):
    out = np.zeros((3, 3))
    return swing_reference(out, start, end, height_m=height, progress=progress,
                           duration_s=duration).copy()


def test_swing_path_ends_apex_and_rest():
    start, end = np.array([0.1, 0.2, 0.02]), np.array([0.25, 0.15, 0.017])
    first, last = _path(0.0, start, end), _path(1.0, start, end)
    np.testing.assert_allclose(first[0], start)
    np.testing.assert_allclose(last[0], end)
    np.testing.assert_allclose(first[1:], 0.0, atol=1e-12)  # at rest, no acceleration
    np.testing.assert_allclose(last[1:], 0.0, atol=1e-12)
    mid = _path(0.5, start, end)
    assert mid[0, 2] == pytest.approx(0.02 + 0.08)  # the apex above the higher end
    assert mid[1, 2] == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(mid[0, :2], (start[:2] + end[:2]) / 2)


def test_swing_path_is_continuous_and_its_derivatives_match_finite_differences():
    start, end, duration = np.array([0.1, 0.2, 0.02]), np.array([0.3, 0.1, 0.0]), 0.2
    dt = 1e-5
    times = np.arange(0.0, duration + dt / 2, dt)
    paths = np.array([_path(t / duration, start, end, duration) for t in times])
    position, velocity, acceleration = paths[:, 0], paths[:, 1], paths[:, 2]
    fd_velocity = np.gradient(position, dt, axis=0)
    fd_acceleration = np.gradient(velocity, dt, axis=0)
    np.testing.assert_allclose(fd_velocity[1:-1], velocity[1:-1], atol=2e-4)
    # Peak acceleration about 40 m/s^2: the central difference agrees within 0.1 %.
    np.testing.assert_allclose(fd_acceleration[1:-1], acceleration[1:-1], atol=5e-2)
    # No jumps anywhere (the apex, where the vertical halves meet, included).
    assert np.abs(np.diff(position, axis=0)).max() < 2e-5
    assert np.abs(np.diff(velocity, axis=0)).max() < 1e-3
    assert np.abs(np.diff(acceleration, axis=0)).max() < 0.1


def _planner(max_step=0.2):
    offsets = {"FL": np.array([0.19, 0.16]), "FR": np.array([0.19, -0.16]),
               "RL": np.array([-0.19, 0.16]), "RR": np.array([-0.19, -0.16])}
    return FootholdPlanner(offsets, com_height_m=0.3, max_step_m=max_step)


def _foothold(planner, leg="FL", com=(0.0, 0.0), yaw=0.0, v_cmd=(0.0, 0.0), v=(0.0, 0.0),
              yaw_rate=0.0, left=0.0, stance=0.3):
    return planner.foothold(leg, com_xy=np.array(com), yaw_rad=yaw,
                            velocity_cmd=np.array(v_cmd), velocity=np.array(v),
                            yaw_rate_cmd=yaw_rate, time_to_touchdown_s=left, stance_s=stance)


def test_foothold_at_rest_is_under_the_hip():
    np.testing.assert_allclose(_foothold(_planner(), com=(1.0, 2.0)), [1.19, 2.16])


def test_foothold_raibert_term_and_time_to_touchdown():
    # 0.5 m/s, 0.1 s to touch-down, 0.3 s stance: the hip 5 cm on, the foot 7.5 cm ahead.
    p = _foothold(_planner(), v_cmd=(0.5, 0.0), v=(0.5, 0.0), left=0.1)
    np.testing.assert_allclose(p, [0.19 + 0.05 + 0.075, 0.16])


def test_foothold_capture_point_feedback():
    gain = math.sqrt(0.3 / 9.81)
    assert _planner().feedback_gain == pytest.approx(gain)
    slow = _foothold(_planner(), v_cmd=(0.5, 0.0), v=(0.3, 0.1))
    np.testing.assert_allclose(slow, [0.19 + 0.075 - 0.2 * gain, 0.16 + 0.1 * gain])


def test_foothold_turns_with_the_yaw_rate():
    # Turning at 1 rad/s in place: the hip offset turns by w (t_td + T_st / 2) = 0.25 rad.
    p = _foothold(_planner(), yaw=0.1, yaw_rate=1.0, left=0.1)
    c, s = math.cos(0.35), math.sin(0.35)
    np.testing.assert_allclose(p, [c * 0.19 - s * 0.16, s * 0.19 + c * 0.16])


def test_foothold_is_clamped_to_the_step_length():
    p = _foothold(_planner(max_step=0.1), v_cmd=(2.0, 0.0), v=(2.5, 0.0))
    assert np.linalg.norm(p - [0.19, 0.16]) == pytest.approx(0.1)
    with pytest.raises(ConfigurationError, match=r"max_step_m: expected a value in \(0, inf\]"):
        _planner(max_step=0.0)
