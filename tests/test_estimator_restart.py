"""Both estimators at start-up and after a gap: what a sample needs to start one (the field
named), a start without the IMU's quaternion (roll and pitch from the accelerometer), a start
with a foot in the air, and a fresh start from the first trustworthy sample after the inputs
were untrustworthy for longer than the trust limit (instead of integrating across the gap)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from tests.synthetic_records import LOADED, expected_height, pose, record, run, started
from wbc.core.errors import ConfigurationError
from wbc.estimation.invariant_ekf import InvariantEkf
from wbc.estimation.state_estimator import StateEstimator
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS, Go2Description

ESTIMATORS = [InvariantEkf, StateEstimator]


@pytest.mark.parametrize("kind", ESTIMATORS)
def test_a_sample_that_cannot_start_the_estimator_is_named(kind):
    estimator = kind()
    good = record(pose(), tick=0)
    assert estimator.start_problem(good) == ""
    assert estimator.start_problem(None) == "no sensor sample"
    broken = record(pose(), tick=0)
    broken.q[4] = np.nan
    assert estimator.start_problem(broken) == "q: non-finite reading at FR_thigh_joint"
    broken = record(pose(), tick=0)
    broken.gyroscope_rad_s[:] = np.nan
    assert estimator.start_problem(broken) == "gyroscope_rad_s: non-finite reading [nan, nan, nan]"
    with pytest.raises(ConfigurationError, match="^cannot start the state estimator: q: "):
        estimator.reset(_with_nan_joint())
    assert not estimator.started


def _with_nan_joint():
    broken = record(pose(), tick=0)
    broken.dq[0] = np.nan
    broken.q[0] = np.nan
    return broken


def test_the_invariant_ekf_starts_without_a_quaternion_the_linear_filter_waits_for_one():
    q = pose(roll_deg=3.0, pitch_deg=-2.0)
    sample = record(q, tick=0)
    sample.imu_quaternion_wxyz[:] = np.nan
    assert StateEstimator().start_problem(sample).startswith(
        "imu_quaternion_wxyz: expected a unit quaternion (w, x, y, z), received [nan, nan, nan, "
        "nan] (norm nan)")
    estimator = InvariantEkf()
    assert estimator.start_problem(sample) == ""
    estimate = estimator.reset(sample)
    assert estimator.start_note == ("started without the IMU quaternion: roll and pitch from the "
                                    "accelerometer, yaw 0")
    # Roll and pitch from gravity as the accelerometer reads it, exactly (noise-free record).
    np.testing.assert_allclose(estimate.q[3:7], q[3:7], atol=1e-9)
    assert estimate.q[2] == pytest.approx(expected_height(q), abs=1e-6)
    # Neither the quaternion nor gravity: the accelerometer is named too.
    sample.accelerometer_m_s2[:] = np.nan
    assert "and accelerometer_m_s2: expected gravity's 9.81 m/s^2 at rest" in (
        estimator.start_problem(sample))


@pytest.mark.parametrize("kind", ESTIMATORS)
def test_after_a_gap_longer_than_the_trust_limit_it_starts_again_from_the_fresh_sample(kind):
    q = pose()
    estimator = started(kind, q)
    run(estimator, q, 100)
    # 0.5 s without samples: past the trust limit (the loop stops using the estimate).
    for _ in range(500):
        estimate = estimator.update(None, LOADED)
    assert not estimate.usable and estimator.restarts == 0
    # The first trustworthy sample, in another posture (the robot sagged meanwhile): a fresh
    # start on four loaded feet at the base's place, not a filter pulled towards it.
    lower = q.copy()
    lower[7:] = pose()[7:] * 1.1
    assert abs(expected_height(lower) - expected_height(q)) > 0.02
    estimate = estimator.update(record(lower, tick=700), LOADED)
    assert estimator.restarts == 1 and estimate.usable and estimate.trusted
    assert estimate.q[2] == pytest.approx(expected_height(lower), abs=1e-6)
    np.testing.assert_allclose(estimate.q[:2], [0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(estimate.v, np.zeros(18), atol=1e-6)
    estimate = run(estimator, lower, 200, first_tick=701)
    assert estimate.q[2] == pytest.approx(expected_height(lower), abs=1e-4)
    assert estimator.restarts == 1


@pytest.mark.parametrize("kind", ESTIMATORS)
def test_a_start_with_a_foot_in_the_air_puts_the_other_three_on_the_floor(kind):
    q = pose()
    raised = q.copy()
    raised[7 + 4] += 0.4  # FR thigh back and calf folded: the FR foot 0.17 m off the floor
    raised[7 + 5] -= 1.0
    # Its foot sensor reads no load (the others about 40 N).
    estimator = kind()
    estimate = estimator.reset(record(raised, tick=0, feet=np.array([110.0, 0.0, 110.0, 110.0])))
    model = Go2Description.default().model
    data = model.createData()
    pin.framesForwardKinematics(model, data, estimate.q)
    heights = {leg: data.oMf[model.getFrameId(FOOT_FRAMES[leg])].translation[2]
               for leg in LEGS}
    assert heights["FR"] > FOOT_RADIUS_M + 0.1
    for leg in ("FL", "RL", "RR"):
        assert heights[leg] == pytest.approx(FOOT_RADIUS_M, abs=1e-6)
