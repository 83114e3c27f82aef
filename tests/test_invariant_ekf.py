"""The invariant EKF on synthetic sensor records and in closed loop: statics, bias, faults
(as the linear filter's), free feet, covariance, allocation, configuration errors."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from actions import GoalStatus, HighFiveGoal
from sim.control_loop import ControlLoop
from sim.run_recorder import MetricsHook
from tests.synthetic_records import (
    LOADED,
    expected_height,
    pose,
    record,
    run,
    started,
)
from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError
from wbc.estimation.invariant_ekf import InvariantEkf, InvariantEkfConfig
from wbc.estimation.state_estimate import (
    ACCEL_BAD,
    GYRO_BAD,
    JOINTS_BAD,
    NO_DATA,
    QUATERNION_NON_FINITE,
    QUATERNION_TIMEOUT,
    STALE,
)
from wbc.estimation.state_estimator import StateEstimator
from wbc.model.leg_kinematics import LegKinematics
from wbc.robot_io.sensor_record import SensorRecord


def roll_pitch_yaw_deg(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q[3:7]
    return np.degrees(pin.rpy.matrixToRpy(pin.Quaternion(w, x, y, z).toRotationMatrix()))






# ---------------------------------------------------------------------------- statics


def test_a_robot_at_rest_stays_where_its_feet_put_it():
    q = pose()
    estimator = started(InvariantEkf, q)
    estimate = run(estimator, q, 2000)
    assert estimate.trusted and estimate.usable and estimate.faults == ""
    np.testing.assert_allclose(estimate.q[:2], [0.0, 0.0], atol=1e-9)
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-9)
    np.testing.assert_array_equal(estimate.q[7:], q[7:])
    np.testing.assert_allclose(estimate.v, np.zeros(18), atol=1e-9)
    np.testing.assert_array_equal(estimate.contact, np.ones(4))
    np.testing.assert_allclose(estimator.gyro_bias, np.zeros(3), atol=1e-9)


def test_a_tilted_start_keeps_its_tilt_and_the_heading_starts_at_zero():
    q = pose(roll_deg=4.0, pitch_deg=-3.0, yaw_deg=30.0)
    estimator = InvariantEkf()
    estimate = estimator.reset(record(q, tick=0), base_xy=(1.0, -2.0))
    np.testing.assert_allclose(roll_pitch_yaw_deg(estimate.q), [4.0, -3.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(estimate.q[:2], [1.0, -2.0], atol=1e-9)
    # The feet's kinematics and gravity agree with the start: nothing moves in 2 s.
    estimate = run(estimator, q, 2000)
    np.testing.assert_allclose(roll_pitch_yaw_deg(estimate.q), [4.0, -3.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(estimate.q[:2], [1.0, -2.0], atol=1e-9)
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)
    np.testing.assert_allclose(estimate.v[:6], np.zeros(6), atol=1e-9)
    kept = InvariantEkf().reset(record(q, tick=0), keep_yaw=True)
    np.testing.assert_allclose(kept.q[3:7], q[3:7], atol=1e-12)


def test_a_gyroscope_bias_is_learnt_while_roll_and_pitch_stay_level():
    q = pose()
    bias = np.array([0.01, -0.02, 0.005])  # rad/s: 0.6 to 1.1 deg/s, on every axis
    estimator = started(InvariantEkf, q)
    worst = np.zeros(3)
    for tick in range(1, 10_001):
        estimate = estimator.update(record(q, tick=tick, gyro=bias), LOADED)
        worst = np.maximum(worst, np.abs(roll_pitch_yaw_deg(estimate.q)))
    # Roll and pitch from gravity, the yaw rate from the standing feet: all three learnt
    # (measured: within 1.4e-4 rad/s after 10 s).
    np.testing.assert_allclose(estimator.gyro_bias, bias, atol=3e-4)
    np.testing.assert_allclose(estimate.v[3:6], np.zeros(3), atol=3e-4)
    # Measured: roll and pitch within 0.07 deg while it is learnt, the heading 0.012 deg off.
    assert worst[0] < 0.1 and worst[1] < 0.1 and worst[2] < 0.03
    np.testing.assert_allclose(estimate.q[:2], [0.0, 0.0], atol=1e-3)
    np.testing.assert_allclose(estimate.v[:3], np.zeros(3), atol=5e-4)


def test_the_imu_quaternion_is_read_at_the_start_only():
    q = pose()
    estimator = started(InvariantEkf, q)
    for tick in range(1, 2002):  # 2 s: longer than quaternion_timeout_s
        broken = record(q, tick=tick)
        # NaN, or a unit quaternion 37 deg away from the truth, in turn (NaN last).
        broken.imu_quaternion_wxyz[:] = np.nan if tick % 2 else [0.9, 0.3, 0.3, 0.1]
        estimate = estimator.update(broken, LOADED)
        assert estimate.trusted and estimate.usable
        assert not estimate.flags & QUATERNION_TIMEOUT
    assert estimate.flags & QUATERNION_NON_FINITE
    assert estimate.faults.startswith("IMU quaternion non-finite ([nan, nan, nan, nan])")
    np.testing.assert_allclose(estimate.q[:7], started(InvariantEkf, q).estimate.q[:7], atol=1e-9)


@pytest.mark.parametrize("floor", [False, True], ids=["invariant", "flat floor"])
def test_a_start_tilted_by_the_imu_quaternion_alone_is_explained_without_moving_the_base(floor):
    """The IMU's quaternion says roll 2, pitch -1 deg; the accelerometer and the legs say
    level. At rest the accelerometer cannot tell a tilt from its bias: the filter explains
    the reading with both. A flat floor under the feet (optional) tells the tilt."""
    q = pose()
    estimator = InvariantEkf(foot_height_noise_m=2e-3 if floor else 0.0)
    first = record(pose(roll_deg=2.0, pitch_deg=-1.0), tick=0)
    first.accelerometer_m_s2[:] = [0.0, 0.0, 9.81]
    estimator.reset(first)
    estimate = run(estimator, q, 3000)
    x, y, z, w = estimate.q[3:7]
    rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
    unexplained = rotation.T @ [0.0, 0.0, 9.81] + estimator.accel_bias - [0.0, 0.0, 9.81]
    # Measured: 95 % of the 0.38 m/s^2 explained after 3 s (by a fifth of the tilt and the
    # bias), all of it by the tilt on the floor (roll and pitch within 0.001 deg).
    assert np.linalg.norm(unexplained) < 0.1 * 9.81 * math.radians(math.hypot(2.0, 1.0))
    if floor:
        np.testing.assert_allclose(roll_pitch_yaw_deg(estimate.q)[:2], [0.0, 0.0], atol=0.01)
    # The base stays where the start put it (measured: 1.4 mm on the floor, 0.1 mm without;
    # 12 mm if the start's covariance forgot that the position is known and the tilt not).
    np.testing.assert_allclose(estimate.q[:2], [0.0, 0.0], atol=2e-3 if floor else 5e-4)


# ---------------------------------------------------------------------------- faults


def test_stale_missing_and_non_finite_samples_are_handled_as_the_linear_filter_does():
    q = pose()
    estimators = [started(InvariantEkf, q), StateEstimator()]
    estimators[1].reset(record(q, tick=0))
    script: list[SensorRecord | None] = [record(q, tick=t) for t in range(1, 11)]
    script += [record(q, tick=10)] * 10 + [None]  # 10 stale, then none: 11 ms untrusted
    script += [record(q, tick=t) for t in range(11, 14)]
    bad_joint, bad_gyro, bad_accel = (record(q, tick=t) for t in (14, 15, 16))
    bad_joint.q[4] = np.nan
    bad_gyro.gyroscope_rad_s[1] = np.nan
    bad_accel.accelerometer_m_s2[2] = np.inf
    script += [bad_joint, bad_gyro, bad_accel, record(q, tick=17)]
    seen = []
    for step, sample in enumerate(script):
        ours, theirs = (e.update(sample, LOADED) for e in estimators)
        assert (ours.flags, ours.trusted, ours.usable, ours.faults) == (
            theirs.flags, theirs.trusted, theirs.usable, theirs.faults), step
        assert ours.untrusted_s == pytest.approx(theirs.untrusted_s, abs=1e-12)
        np.testing.assert_array_equal(ours.contact, theirs.contact)
        seen.append((ours.flags, ours.trusted, ours.usable, ours.faults))
        if step == 20:
            assert ours.untrusted_s == pytest.approx(0.011)
    stale = "stale sample (tick 10 repeated)"
    assert seen[19] == (STALE, False, True, stale)  # the 10th stale sample: 10 ms
    assert seen[20] == (NO_DATA, False, False, "no sensor sample this period")
    assert seen[21] == (0, True, True, "")
    assert seen[24] == (JOINTS_BAD, False, True, "joint readings non-finite at [4]")
    assert seen[25][:3] == (GYRO_BAD, False, True)
    assert seen[26][:3] == (ACCEL_BAD, True, True)  # predicting without it
    # Through it all the estimate stays at rest, with the last good joints.
    estimate = estimators[0].estimate
    np.testing.assert_array_equal(estimate.q[7:], q[7:])
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)
    np.testing.assert_allclose(estimate.v[:6], np.zeros(6), atol=1e-9)


@pytest.mark.parametrize(("reading", "words"), [
    (1000.0, "FR foot-force sensor at full scale (1000): contact from the schedule"),
    (0.0, "FR foot-force sensor stuck at 0: contact from the schedule")])
def test_a_broken_foot_sensor_is_reported_as_the_linear_filter_does(reading, words):
    q = pose()
    ours, theirs = started(InvariantEkf, q), StateEstimator()
    theirs.reset(record(q, tick=0))
    for tick in range(1, 61):  # 60 ms of the same reading on a loaded foot
        broken = record(q, tick=tick)
        broken.foot_force[1] = reading
        estimate = ours.update(broken, LOADED)
        assert estimate.faults == theirs.update(broken, LOADED).faults
    assert estimate.faults == words and estimate.usable
    assert estimate.contact[1] == 1.0  # the schedule's


# ---------------------------------------------------------------------------- contact


def test_a_foot_the_schedule_lets_go_follows_the_kinematics_and_moves_nothing():
    q = pose()
    estimator = started(InvariantEkf, q)
    start = estimator.estimate.q[:3].copy()
    swing = LOADED.copy()
    swing[1] = 0.0  # FR in the air
    raised = q.copy()
    raised[7 + 4:7 + 6] += [0.4, -0.6]  # FR thigh and calf: the foot goes up and forward
    legs = LegKinematics()
    legs.compute(raised[7:])
    tick = 0
    for tick in range(1, 501):
        sample = record(raised, tick=tick)
        sample.foot_force[1] = 10.0  # unloaded
        estimate = estimator.update(sample, swing)
    assert estimate.contact[1] == 0.0
    np.testing.assert_allclose(estimate.q[:3], start, atol=1e-9)
    np.testing.assert_allclose(estimator.foot_positions[1], start + legs.foot_position[1],
                               atol=1e-9)
    lowered = record(q, tick=tick + 1)  # down, still unloaded
    lowered.foot_force[1] = 10.0
    estimator.update(lowered, swing)
    estimate = run(estimator, q, 500, first_tick=tick + 2)  # loaded again
    np.testing.assert_allclose(estimate.q[:3], start, atol=1e-9)
    np.testing.assert_array_equal(estimate.contact, np.ones(4))


def test_the_covariance_stays_symmetric_and_positive():
    q = pose()
    estimator = started(InvariantEkf, q)
    bounds = LOADED.copy()
    rng = np.random.default_rng(3)
    for tick in range(1, 3001):
        bounds[:] = 200.0
        bounds[(tick // 250) % 4] = 15.0 * (tick % 2)  # one foot ramped or released
        sample = record(q, tick=tick, gyro=rng.normal(0.0, 0.004, 3))
        sample.accelerometer_m_s2 += rng.normal(0.0, 0.03, 3)
        estimator.update(sample, bounds)
    P = estimator.covariance
    np.testing.assert_array_equal(P, P.T)
    assert np.linalg.eigvalsh(P).min() > -1e-12
    assert np.all(np.isfinite(estimator.estimate.q))




# ---------------------------------------------------------------------------- bad input


def test_bad_configuration_names_the_field():
    with pytest.raises(ConfigurationError, match=r"^unknown estimator parameter\(s\) "
                                                 r"\['tau'\]; valid parameters: quaternion_"):
        InvariantEkf(tau=1.0)
    with pytest.raises(ConfigurationError, match=r"^gyroscope_noise: expected a value in "
                                                 r"\(1e-09, 10\], received -1"):
        InvariantEkf(gyroscope_noise=-1.0)
    with pytest.raises(ConfigurationError, match=r"^contact_noise: expected a number, "
                                                 r"received '0.1'"):
        InvariantEkfConfig(contact_noise="0.1")  # type: ignore[arg-type]
    with pytest.raises(NonFiniteError, match=r"^kinematics_noise_rad: expected a finite"):
        InvariantEkfConfig(kinematics_noise_rad=math.nan)
    with pytest.raises(ConfigurationError, match=r"^foot_force_off_n: expected less than "
                                                 r"foot_force_on_n \(20 N\), received 30"):
        InvariantEkfConfig(foot_force_off_n=30.0)
    with pytest.raises(ConfigurationError, match=r"^use_foot_force: expected true or false"):
        InvariantEkfConfig(use_foot_force=1)  # type: ignore[arg-type]
    with pytest.raises(UnknownNameError, match=r"^unknown estimator parameter 'nope'; valid "
                                               r"estimator parameters: quaternion_tolerance, "):
        InvariantEkfConfig(nope=1)  # type: ignore[call-arg]
    with pytest.raises(ConfigurationError, match=r"^control_period_s: expected a value in "
                                                 r"\(0, 0.1\], received 0"):
        InvariantEkf(control_period_s=0.0)
    estimator = InvariantEkf(InvariantEkfConfig(contact_noise=2e-3), swing_noise_scale=50.0)
    assert (estimator.config.contact_noise, estimator.config.swing_noise_scale) == (2e-3, 50.0)
    with pytest.raises(ConfigurationError, match=r"^InvariantEkf.update: call reset\(record\) "
                                                 r"first"):
        estimator.update(record(pose(), tick=1), LOADED)
    broken = record(pose(), tick=0)
    broken.imu_quaternion_wxyz[:] = [2.0, 0.0, 0.0, 0.0]
    broken.accelerometer_m_s2[:] = np.nan  # nor gravity to take roll and pitch from
    with pytest.raises(ConfigurationError, match=r"^cannot start the state estimator: "
                                                 r"imu_quaternion_wxyz: expected a unit "
                                                 r"quaternion \(w, x, y, z\), received "
                                                 r"\[2.0, 0.0, 0.0, 0.0\] \(norm 2\), and "
                                                 r"accelerometer_m_s2: expected gravity's"):
        estimator.reset(broken)
    estimator.reset(record(pose(), tick=0))
    with pytest.raises(ConfigurationError, match=r"^normal_force_bounds: expected 4 numbers"):
        estimator.update(record(pose(), tick=1), np.zeros(3))


# ---------------------------------------------------------------------------- closed loop


def test_a_high_five_on_the_invariant_ekf_succeeds_and_its_estimate_is_measured():
    estimator = InvariantEkf()
    loop = ControlLoop.simulated(estimator=estimator)
    assert loop.estimator is estimator
    loop.spin_for(0.3)  # the plant spawns without contact forces: its feet settle first
    metrics = MetricsHook(loop, lambda: phases[-1] if phases else "")
    loop.hooks.append(metrics)
    phases: list[str] = []
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=0.40, hold_seconds=2), timeout=30.0,
        feedback_callback=lambda message: phases.append(message.feedback.phase))
    assert result.status is GoalStatus.SUCCEEDED, result.result.message
    s = metrics.metrics.summary(1.0)
    # Measured (default plant and sensors, seed 0): tracking 1.8 mm RMS, holding 1.4 mm,
    # tilt 0.6 deg; velocity error 0.5 mm/s RMS (1.6 mm/s at most), height 1.0 mm (the feet
    # sink 0.7 mm into MuJoCo's soft floor), roll and pitch 0.04 deg, horizontal drift
    # 0.3 mm at most, yaw 0.015 deg.
    assert s.raised_foot_rms_mm < 3.0 and s.holding_rms_mm < 2.5
    assert s.max_base_tilt_deg < 1.0
    assert s.estimate_velocity_rms_m_s < 1.5e-3 and s.estimate_velocity_max_m_s < 5e-3
    assert s.estimate_height_max_mm < 2.0
    assert max(s.estimate_roll_max_deg, s.estimate_pitch_max_deg) < 0.15
    assert s.estimate_horizontal_drift_max_mm < 1.0 and abs(s.estimate_yaw_drift_deg) < 0.05
    assert estimator.estimate.faults == "" and estimator.estimate.usable
