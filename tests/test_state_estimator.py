"""The linear state estimator on synthetic sensor records: statics, bias, contacts, faults."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from numba.core.runtime import _nrt_python, rtsys

from tests.synthetic_records import (
    LOADED,
    LOADED_COUNT,
    expected_height,
    pose,
    record,
    run,
    started,
)
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.estimation.estimator_base import sample_values
from wbc.estimation.estimator_config import EstimatorConfig
from wbc.estimation.invariant_ekf import InvariantEkf
from wbc.estimation.kernel_groups import Sample
from wbc.estimation.shared_kernels import check_sample
from wbc.estimation.state_estimate import (
    FOOT_SENSOR,
    JOINTS_BAD,
    NO_DATA,
    QUATERNION_NON_FINITE,
    QUATERNION_NOT_UNIT,
    STALE,
)
from wbc.estimation.state_estimator import StateEstimator
from wbc.model.description import LEGS
from wbc.robot_io.sdk_low_state import SdkLowState, sensor_record_from_message
from wbc.robot_io.sensor_record import SensorRecord

# ---------------------------------------------------------------------------- statics


def test_a_robot_at_rest_is_estimated_at_rest_where_its_feet_put_it():
    q = pose()
    estimator = started(StateEstimator, q)
    estimate = run(estimator, q, 2000)
    assert estimate.trusted and estimate.usable and estimate.faults == ""
    np.testing.assert_allclose(estimate.q[:2], [0.0, 0.0], atol=1e-9)
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-9)
    np.testing.assert_array_equal(estimate.q[7:], q[7:])
    np.testing.assert_allclose(estimate.v, np.zeros(18), atol=1e-9)
    np.testing.assert_array_equal(estimate.contact, np.ones(4))


def test_the_world_starts_with_the_heading_at_zero_unless_told_to_keep_it():
    q = pose(yaw_deg=30.0)
    estimate = StateEstimator().reset(record(q, tick=0), base_xy=(1.0, -2.0))
    np.testing.assert_allclose(estimate.q[3:7], pose()[3:7], atol=1e-12)
    np.testing.assert_allclose(estimate.q[:2], [1.0, -2.0], atol=1e-12)
    kept = StateEstimator().reset(record(q, tick=0), keep_yaw=True)
    np.testing.assert_allclose(kept.q[3:7], q[3:7], atol=1e-12)


def test_a_gyroscope_bias_is_learnt_and_leaves_no_tilt():
    q = pose()
    bias = np.array([0.01, -0.02, 0.005])  # rad/s: 0.6 to 1.1 deg/s
    estimator = started(StateEstimator, q)
    estimate = run(estimator, q, 60_000, gyro=bias)
    np.testing.assert_allclose(estimator.gyro_bias, bias, atol=2e-4)
    np.testing.assert_allclose(estimate.v[3:6], np.zeros(3), atol=2e-4)
    # The IMU's quaternion (level) is followed: the bias tilts the estimate by bias * 0.05 s
    # at first, and not at all once learnt.
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-5)


# ---------------------------------------------------------------------------- contact


def test_a_foot_the_sensor_calls_unloaded_or_the_schedule_lifts_has_no_weight():
    q = pose()
    estimator = started(StateEstimator, q)
    unloaded = record(q, tick=1)
    unloaded.foot_force[1] = 20.0  # FR: below the 40-count release threshold
    estimate = estimator.update(unloaded, LOADED)
    np.testing.assert_array_equal(estimate.contact, [1.0, 0.0, 1.0, 1.0])
    again = record(q, tick=2)
    again.foot_force[1] = 50.0  # between the thresholds: still released (hysteresis)
    assert estimator.update(again, LOADED).contact[1] == 0.0
    again = record(q, tick=3)  # about 110 counts: in contact again
    assert estimator.update(again, LOADED).contact[1] == 1.0
    ramp = LOADED.copy()
    ramp[2] = 15.0  # RL's bound ramped to 15 N: half the schedule's trust
    np.testing.assert_allclose(estimator.update(record(q, tick=4), ramp).contact,
                               [1.0, 1.0, 0.5, 1.0])
    swing = LOADED.copy()
    swing[3] = 0.0
    assert estimator.update(record(q, tick=5), swing).contact[3] == 0.0


def test_schedule_only_mode_ignores_the_foot_sensors():
    q = pose()
    estimator = started(StateEstimator, q, use_foot_force=False)
    for tick in range(1, 201):  # 0.2 s of zeros: a live sensor would be "stuck at 0"
        silent = record(q, tick=tick, feet=0.0)  # no foot sensors: zeros
        np.testing.assert_array_equal(estimator.update(silent, LOADED).contact, np.ones(4))
        assert estimator.estimate.faults == "" and estimator.estimate.flags == 0


# ---------------------------------------------------------------------------- faults


def test_stale_and_missing_samples_are_untrusted_and_unusable_after_the_timeout():
    q = pose()
    estimator = started(StateEstimator, q)  # trust_timeout_s 0.01: ten 1 ms ticks
    run(estimator, q, 10)
    repeated = record(q, tick=10)
    for k in range(10):
        estimate = estimator.update(repeated, LOADED)
        assert estimate.flags & STALE and not estimate.trusted and estimate.usable, k
    assert estimate.faults == "stale sample (tick 10 repeated)"
    estimate = estimator.update(None, LOADED)
    assert estimate.flags & NO_DATA and not estimate.usable
    assert estimate.untrusted_s == pytest.approx(0.011)
    assert estimate.faults == "no sensor sample this period"
    estimate = estimator.update(record(q, tick=11), LOADED)
    assert estimate.trusted and estimate.usable and estimate.faults == ""
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)


def test_the_tick_passes_the_sample_in_its_groups_field_order():
    sample = record(pose(), tick=7)
    group = Sample(*sample_values(True, sample))
    assert group.fresh is True and group.tick == 7.0 and group.stamp_s == sample.stamp_s
    assert group.quaternion is sample.imu_quaternion_wxyz
    assert group.gyroscope is sample.gyroscope_rad_s
    assert group.accelerometer is sample.accelerometer_m_s2
    assert group.q is sample.q and group.dq is sample.dq
    assert group.foot_force is sample.foot_force


def test_time_predicted_without_samples_is_not_predicted_again():
    quat, gyro, accel = np.array([1.0, 0, 0, 0]), np.zeros(3), np.array([0, 0, 9.81])
    joints = np.zeros(12)
    clock = np.array([9.0, 0.009, 0.0, 0.0])  # the last sample: tick 9 at 9 ms

    def step(fresh: bool, tick: int) -> float:
        sample = Sample(fresh, float(tick), tick * 1e-3, quat, gyro, accel, joints, joints,
                        np.zeros(4))
        return check_sample(sample, clock, 1e-3, 0.01)[1]

    assert [step(False, 9) for _ in range(4)] == [1e-3] * 4  # four missing: 4 ms predicted
    assert step(True, 10) == pytest.approx(0.0)  # 10 ms: 1 ms after 9, already predicted
    assert step(True, 11) == pytest.approx(1e-3)
    assert step(True, 11) == pytest.approx(1e-3)  # stale: predicted on
    assert step(True, 13) == pytest.approx(1e-3)  # 2 ms, 1 of them predicted


def test_a_bad_quaternion_is_reported_and_the_gyroscope_carries_the_orientation():
    q = pose()
    estimator = started(StateEstimator, q)
    run(estimator, q, 10)
    bad = record(q, tick=11)
    bad.imu_quaternion_wxyz[:] = np.nan
    estimate = estimator.update(bad, LOADED)
    assert estimate.flags & QUATERNION_NON_FINITE and estimate.trusted and estimate.usable
    assert estimate.faults.startswith("IMU quaternion non-finite ([nan, nan, nan, nan]): "
                                      "orientation from the gyroscope")
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-9)
    long = record(q, tick=12)
    long.imu_quaternion_wxyz *= 1.5
    estimate = estimator.update(long, LOADED)
    assert estimate.flags & QUATERNION_NOT_UNIT
    assert "IMU quaternion not unit (norm 1.5, tolerance 0.01)" in estimate.faults
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-9)


def test_non_finite_joints_make_the_sample_untrusted_and_keep_the_last_good_joints():
    q = pose()
    estimator = started(StateEstimator, q)
    bad = record(q, tick=1)
    bad.q[4] = np.nan
    estimate = estimator.update(bad, LOADED)
    assert estimate.flags & JOINTS_BAD and not estimate.trusted
    assert estimate.faults == "joint readings non-finite at [4]"
    np.testing.assert_array_equal(estimate.q[7:], q[7:])
    assert np.all(np.isfinite(estimate.q)) and np.all(np.isfinite(estimate.v))


@pytest.mark.parametrize(("reading", "words"), [
    (1000.0, "FR foot-force sensor at full scale (1000): contact from the schedule"),
    (0.0, "FR foot-force sensor stuck at 0: contact from the schedule")])
def test_a_broken_foot_sensor_is_distrusted_then_trusted_again(reading, words):
    q = pose()
    estimator = started(StateEstimator, q)
    rng = np.random.default_rng(1)
    tick = 0
    for _ in range(60):  # 60 ms of the same reading on a loaded foot
        tick += 1
        broken = record(q, tick=tick, feet=LOADED_COUNT + rng.integers(-3, 4))
        broken.foot_force[1] = reading
        estimate = estimator.update(broken, LOADED)
    assert estimate.flags & FOOT_SENSOR and estimate.faults == words
    assert estimate.contact[1] == 1.0  # the schedule's: loaded
    for _ in range(499):  # changing, in-range readings: trusted again after 0.5 s
        tick += 1
        estimate = estimator.update(record(q, tick=tick, feet=LOADED_COUNT + tick % 5), LOADED)
    assert estimate.flags & FOOT_SENSOR
    tick += 1
    estimate = estimator.update(record(q, tick=tick, feet=LOADED_COUNT), LOADED)
    assert not estimate.flags and estimate.faults == ""


def test_a_foot_in_the_air_may_read_a_steady_value():
    q = pose()
    estimator = started(StateEstimator, q)
    swing = LOADED.copy()
    swing[1] = 0.0
    for tick in range(1, 200):
        sample = record(q, tick=tick)
        sample.foot_force[1] = 10.0  # FR, in the air
        estimate = estimator.update(sample, swing)
    assert not estimate.flags & FOOT_SENSOR


@pytest.mark.parametrize("kind", [StateEstimator, InvariantEkf], ids=["kf", "inekf"])
def test_the_tick_allocates_nothing_in_compiled_code(kind):
    """numba wraps each array passed from Python once per call (its unboxing); the tick's
    compiled code allocates nothing beyond that."""
    q = pose()
    estimator = started(kind, q)
    records = [record(q, tick=tick) for tick in range(1, 101)]
    estimator.update(records[0], LOADED)
    _nrt_python.memsys_enable_stats()
    try:
        before = rtsys.get_allocation_stats().alloc
        for sample in records[1:]:
            estimator.update(sample, LOADED)
        allocated = rtsys.get_allocation_stats().alloc - before
    finally:
        _nrt_python.memsys_disable_stats()
    # The estimator's own arrays, and the sample's six.
    arrays = sum(isinstance(a, np.ndarray) for a in estimator._tick_arrays) + 6
    assert allocated == 99 * arrays


# ---------------------------------------------------------------------------- from the SDK


def test_a_low_state_message_is_all_the_estimator_needs():
    q = pose()
    low = SdkLowState.from_pinocchio(q, np.zeros(18), foot_force_by_leg=dict.fromkeys(
        LEGS, LOADED_COUNT))
    low.tick = 5
    estimator = StateEstimator()
    estimate = estimator.reset(low.sensor_record())
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-9)
    np.testing.assert_allclose(estimate.q[3:], q[3:], atol=1e-12)
    message = SimpleNamespace(
        imu_state=SimpleNamespace(quaternion=[np.nan] * 4, gyroscope=[0.0] * 3,
                                  accelerometer=[0.0, 0.0, 9.81]),
        motor_state=[SimpleNamespace(q=low.q[k], dq=0.0, tau_est=0.0) for k in range(20)
                     if k < 12] + [SimpleNamespace(q=0.0, dq=0.0, tau_est=0.0)] * 8,
        foot_force=[LOADED_COUNT] * 4, tick=6)
    sample = sensor_record_from_message(message)  # NaN passes to the estimator
    assert sample.tick == 6 and sample.stamp_s == pytest.approx(0.006)
    np.testing.assert_array_equal(sample.q, q[7:])  # SDK order mapped to the description's
    estimate = estimator.update(sample, LOADED)
    assert estimate.flags & QUATERNION_NON_FINITE and estimate.usable


# ---------------------------------------------------------------------------- bad input


def test_bad_input_gets_one_clear_error():
    with pytest.raises(ConfigurationError, match=r"^unknown estimator parameter\(s\) "
                                                 r"\['tau'\]; valid parameters: quaternion_"):
        StateEstimator(tau=1.0)
    with pytest.raises(ConfigurationError, match=r"^foot_force_off_n: expected less than "
                                                 r"foot_force_on_n \(20 N\), received 30"):
        EstimatorConfig(foot_force_off_n=30.0)
    with pytest.raises(ConfigurationError, match=r"^trust_timeout_s: expected a value in "
                                                 r"\[0, 10\], received -1"):
        StateEstimator(trust_timeout_s=-1.0)
    with pytest.raises(ConfigurationError, match=r"^gyroscope_rad_s: expected an array of "
                                                 r"shape \(3,\), received shape \(4,\)"):
        SensorRecord(0.0, 0, [1, 0, 0, 0], [0, 0, 0, 0], np.zeros(3), np.zeros(12),
                     np.zeros(12), np.zeros(12), np.zeros(4))
    with pytest.raises(ConfigurationError, match=r"^tick: expected a whole number"):
        SensorRecord(0.0, 1.5, [1, 0, 0, 0], np.zeros(3), np.zeros(3), np.zeros(12),
                     np.zeros(12), np.zeros(12), np.zeros(4))
    estimator = StateEstimator()
    with pytest.raises(ConfigurationError, match=r"call reset\(record\) first"):
        estimator.update(record(pose(), tick=1), LOADED)
    broken = record(pose(), tick=0)
    broken.imu_quaternion_wxyz[:] = [2.0, 0.0, 0.0, 0.0]
    with pytest.raises(ConfigurationError, match=r"^cannot start the state estimator: "
                                                 r"imu_quaternion_wxyz: expected a unit "
                                                 r"quaternion \(w, x, y, z\), received "
                                                 r"\[2.0, 0.0, 0.0, 0.0\] \(norm 2\)$"):
        estimator.reset(broken)
    broken = record(pose(), tick=0)
    broken.q[0] = np.nan
    with pytest.raises(ConfigurationError, match=r"^cannot start the state estimator: q: "
                                                 r"non-finite reading at FL_hip_joint$"):
        estimator.reset(broken)
    estimator.reset(record(pose(), tick=0))  # still usable after the refusals
    with pytest.raises(ConfigurationError, match=r"^normal_force_bounds: expected 4 numbers"):
        estimator.update(record(pose(), tick=1), np.zeros(3))
    assert estimator.update(record(pose(), tick=1), LOADED).trusted
    with pytest.raises(ConfigurationError, match=r"^record: expected a SensorRecord or None, "
                                                 r"received dict"):
        estimator.update({"q": pose()[7:]}, LOADED)  # type: ignore[arg-type]
    replaced = record(pose(), tick=2)
    replaced.q = [0.0] * 11  # after construction: checked again, the field named
    with pytest.raises(ConfigurationError, match=r"^q: expected an array of shape \(12,\)"):
        estimator.update(replaced, LOADED)
    replaced.q = list(pose()[7:])
    assert estimator.update(replaced, LOADED).trusted
    with pytest.raises(UnknownNameError, match=r"^unknown estimator parameter 'nope'; valid "
                                               r"estimator parameters: quaternion_tolerance, "):
        EstimatorConfig(nope=1)  # type: ignore[call-arg]
