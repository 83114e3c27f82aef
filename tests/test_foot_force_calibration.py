"""The foot-force calibration's model and fits: exact recovery on synthetic data, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wbc.core.errors import ConfigurationError
from wbc.estimation.estimator_config import EstimatorConfig
from wbc.estimation.foot_force_calibration import (
    FootForceCalibration,
    FootForceFit,
    WeightShiftFit,
    static_foot_loads,
)
from wbc.model.description import LEGS

#: A GO2's feet (x, y) [m] standing and its weight [N].
FEET = np.array([[0.173, 0.163], [0.173, -0.163], [-0.214, 0.163], [-0.214, -0.163]])
WEIGHT = 157.8
TRUE = FootForceCalibration(offset=(31.0, 29.0, 30.5, 28.0), gain=(0.25, 0.27, 0.23, 0.26))


def test_calibration_converts_both_ways_and_describes_itself():
    cal = FootForceCalibration(offset=30.0, gain={"FL": 0.25, "FR": 0.5, "RL": 1.0, "RR": 2.0})
    assert cal.offset == (30.0,) * 4
    newtons = np.array([40.0, 40.0, 40.0, 40.0])
    np.testing.assert_allclose(cal.counts(newtons), [40.0, 50.0, 70.0, 110.0])
    np.testing.assert_allclose(cal.newtons(cal.counts(newtons)), newtons)
    assert cal.describe() == ("foot force [counts] = offset + gain x N (given): FL 30 + 0.25/N, "
                              "FR 30 + 0.5/N, RL 30 + 1/N, RR 30 + 2/N")
    assert TRUE.errors_against(TRUE) == (0.0, 0.0)
    gain_error, offset_error_n = FootForceCalibration(offset=32.0, gain=0.275).errors_against(
        FootForceCalibration(offset=30.0, gain=0.25))
    assert gain_error == pytest.approx(0.1) and offset_error_n == pytest.approx(8.0)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"gain": 0.0}, r"^foot_force_gain\[FL\]: expected a value in \(0, 32767\], received 0$"),
    ({"gain": (1.0, 1.0, 1.0)}, (r"^foot_force_gain: expected one number or 4 \(FL, FR, RL, "
                                 r"RR\), received 3: \[1.0, 1.0, 1.0\]")),
    ({"offset": {"FL": 1, "FR": 1, "RL": 1, "XX": 1}},
     (r"^foot_force_offset: expected a number for each of FL, FR, RL, RR, received .* "
      r"\(unknown \['XX'\]\) \(missing \['RR'\]\)")),
    ({"offset": "ten"}, r"^foot_force_offset: expected one number, 4 numbers"),
    ({"offset": (1.0, math.nan, 1.0, 1.0)}, r"^foot_force_offset\[FR\]"),
])
def test_bad_calibration_names_the_field_and_the_leg(kwargs, message):
    with pytest.raises(ConfigurationError, match=message):
        FootForceCalibration(**kwargs)


def test_estimator_config_holds_the_calibration_and_thresholds_in_newtons():
    config = EstimatorConfig()
    # The defaults are the 60 / 40 counts of before on the simulated GO2's 10 + 2.5 counts/N.
    cal = config.foot_calibration()
    np.testing.assert_allclose(cal.counts([config.foot_force_on_n] * 4), 60.0)
    np.testing.assert_allclose(cal.counts([config.foot_force_off_n] * 4), 40.0)
    config = EstimatorConfig(foot_force_offset=30, foot_force_gain=[0.25, 0.25, 0.3, 0.3])
    assert config.foot_force_gain == (0.25, 0.25, 0.3, 0.3)
    with pytest.raises(ConfigurationError, match=r"^foot_force_gain\[RL\]: expected a value "):
        EstimatorConfig(foot_force_gain=[0.25, 0.25, -1.0, 0.3])
    with pytest.raises(ConfigurationError, match=r"^foot_force_full_scale: expected more than the "
                                                 r"count at foot_force_on_n \(1010\), received "
                                                 r"1000"):
        EstimatorConfig(foot_force_gain=50.0)
    with pytest.raises(ConfigurationError, match=r"^weight_high_fraction: expected a value in "
                                                 r"\(1, 100\], received 0.95$"):
        EstimatorConfig(weight_high_fraction=0.95)


def test_least_squares_fit_recovers_offset_and_gain_exactly():
    rng = np.random.default_rng(1)
    fit = FootForceFit()
    for _ in range(50):
        loads = rng.uniform(10.0, 60.0, 4)
        fit.add(TRUE.counts(loads), loads)
    result = fit.result()
    np.testing.assert_allclose(result.offsets, TRUE.offsets, atol=1e-9)
    np.testing.assert_allclose(result.gains, TRUE.gains, rtol=1e-12)
    assert result.source == "learnt"


def test_least_squares_fit_refuses_what_it_cannot_tell():
    fit = FootForceFit()
    with pytest.raises(ConfigurationError, match=r"^foot-force fit: expected at least 10 "
                                                 r"samples, received 0"):
        fit.result()
    for k in range(20):  # every foot still: the gain cannot be told from the offset
        fit.add(TRUE.counts(np.full(4, 40.0)), np.array([40.0, 40.0, 40.0, 40.0 + k]))
    with pytest.raises(ConfigurationError, match=r"the load on a foot must change by at least "
                                                 r"2 N .*received FL 0 N, FR 0 N, RL 0 N: "):
        fit.result()
    with pytest.raises(ConfigurationError, match=r"^newtons: expected 4 finite numbers \(FL, FR, "
                                                 r"RL, RR\), received \[1.0, nan, 1.0, 1.0\]"):
        fit.add(np.ones(4), np.array([1.0, math.nan, 1.0, 1.0]))
    falling = FootForceFit()
    for k in range(20):  # counts that fall as the load grows
        falling.add(100.0 - np.full(4, float(k)), np.full(4, float(k)))
    with pytest.raises(ConfigurationError, match=r"expected counts that grow with the load, "
                                                 r"received gains FL -1, FR -1"):
        falling.result()


def test_static_loads_carry_the_weight_about_the_centre_of_pressure():
    zmp = np.array([-0.01, 0.02])
    loads = static_foot_loads(FEET, zmp, WEIGHT)
    assert loads.sum() == pytest.approx(WEIGHT)
    np.testing.assert_allclose(loads @ FEET / WEIGHT, zmp, atol=1e-12)


@pytest.mark.parametrize("turn_deg", [0.0, 11.0, -16.0])
def test_weight_shift_fit_recovers_gains_offsets_and_the_turn_exactly(turn_deg):
    """Counts made by the true calibration from loads whose centre of pressure is the
    rigid-body one turned by ``turn_deg`` round the circle: recovered to rounding."""
    fit = WeightShiftFit(WEIGHT)
    centre = np.array([-0.046, 0.0])
    turn = math.radians(turn_deg)
    rotation = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    for phase in np.linspace(0.0, 2.0 * math.pi, 400, endpoint=False):
        zmp = centre + 0.045 * np.array([math.cos(phase), math.sin(phase)])
        true_zmp = centre + rotation @ (zmp - centre)
        fit.add(TRUE.counts(static_foot_loads(FEET, true_zmp, WEIGHT)), FEET, zmp)
    result = fit.result()
    np.testing.assert_allclose(result.gains, TRUE.gains, rtol=1e-9)
    np.testing.assert_allclose(result.offsets, TRUE.offsets, atol=1e-7)
    assert fit.phase_deg == pytest.approx(turn_deg, abs=1e-7)
    assert np.all(fit.spread_n() > 10.0)


def test_weight_shift_fit_refuses_swapped_feet_and_still_loads():
    still = WeightShiftFit(WEIGHT)
    for _ in range(20):
        still.add(TRUE.counts(static_foot_loads(FEET, np.zeros(2), WEIGHT)), FEET, np.zeros(2))
    with pytest.raises(ConfigurationError, match=r"the load on a foot must change by at least 2 N "
                                                 r".*received FL 0 N, FR 0 N, RL 0 N, RR 0 N: "
                                                 r"shift the robot's weight further"):
        still.result()
    swapped = WeightShiftFit(WEIGHT)  # the sensors' feet in another order (FR, FL, RR, RL)
    for phase in np.linspace(0.0, 2.0 * math.pi, 100, endpoint=False):
        zmp = 0.045 * np.array([math.cos(phase), math.sin(phase)])
        counts = TRUE.counts(static_foot_loads(FEET, zmp, WEIGHT))
        swapped.add(counts[[1, 0, 3, 2]], FEET, zmp)
    with pytest.raises(ConfigurationError, match=r"the counts do not follow the weight's shift "
                                                 r".*check the feet's order"):
        swapped.result()
    with pytest.raises(ConfigurationError, match=r"^feet_xy: expected finite numbers of shape "
                                                 r"\(4, 2\)"):
        swapped.add(np.ones(4), np.ones((2, 4)), np.zeros(2))
    assert LEGS == ("FL", "FR", "RL", "RR")


def test_an_episode_calibrates_only_what_it_estimates():
    from sim.episode import Episode, EpisodeError

    with pytest.raises(EpisodeError, match=r"calibrate_s: calibrates the sensors the estimator "
                                           r"reads: expected state 'estimate', received 'truth'"):
        Episode(state="truth", calibrate_s=2.0)
    with pytest.raises(EpisodeError, match=r"calibrate_s: expected 0 \(none\) or at least 0.2 s, "
                                           r"received 0.1"):
        Episode(calibrate_s=0.1)
    assert Episode(calibrate_s=2.0).calibrate_s == 2.0


def test_invariant_ekf_takes_the_accelerometer_bias_and_tilt_measured_at_rest():
    import pinocchio as pin

    from tests.synthetic_records import LOADED, pose, record, started
    from wbc.estimation.invariant_ekf import InvariantEkf

    estimator = started(InvariantEkf)
    up = np.array([0.02, -0.01, 1.0])
    up /= np.linalg.norm(up)

    def feet_in_base() -> np.ndarray:
        x, y, z, w = estimator.estimate.q[3:7]
        rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
        return (estimator.foot_positions - estimator.estimate.q[:3]) @ rotation

    before = feet_in_base()
    turn = estimator.set_imu_at_rest([0.1, -0.05, 0.02], up)
    assert math.degrees(turn) == pytest.approx(math.degrees(math.atan(math.hypot(0.02, 0.01))),
                                               rel=1e-6)
    np.testing.assert_allclose(estimator.accel_bias, [0.1, -0.05, 0.02])
    assert estimator.covariance[26, 26] == pytest.approx(0.005 ** 2)
    assert estimator.covariance[26, 0] == 0.0
    estimate = estimator.update(record(pose(), tick=1), LOADED)
    # The feet turned with the base: their base-frame places are what the legs measure.
    np.testing.assert_allclose(feet_in_base(), before, atol=2e-4)
    x, y, z, w = estimate.q[3:7]
    rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
    np.testing.assert_allclose(rotation.T @ [0.0, 0.0, 1.0], up, atol=2e-4)  # one tick later
    with pytest.raises(ConfigurationError, match=r"^up_body: expected a direction, received "
                                                 r"\[0.0, 0.0, 0.0\]"):
        estimator.set_imu_at_rest(np.zeros(3), np.zeros(3))
    with pytest.raises(ConfigurationError, match=r"^accel_bias_m_s2"):
        estimator.set_imu_at_rest([1.0, 2.0], up)
    with pytest.raises(ConfigurationError, match=r"call reset\(record\) first"):
        InvariantEkf().set_imu_at_rest(np.zeros(3), up)
