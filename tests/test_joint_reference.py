"""The desired joint state: the plan integrated, bounded around and decaying to the measurement."""

import numpy as np
import pytest

from wbc.controller.joint_reference import JointReference
from wbc.core.errors import ConfigurationError

DT = 1e-3


def test_follows_a_plan_the_plant_follows():
    """A plant that does what the plan says: the reference is the plan, one period ahead."""
    ref = JointReference(2, max_position_error_rad=0.05, max_velocity_error_rad_s=1.0,
                         leak_time_s=0.2)
    q, dq = np.zeros(2), np.zeros(2)
    ref.reset(q, dq)
    qdd = np.array([2.0, -1.0])
    for _ in range(500):
        ref.advance(q, dq, qdd, DT)
        dq = dq + DT * qdd  # the plant integrates the same way
        q = q + DT * dq
        np.testing.assert_allclose(ref.dq_des, dq, atol=1e-12)
        np.testing.assert_allclose(ref.q_des, q, atol=1e-12)


@pytest.mark.parametrize("leak_time_s", [0.0, 0.2])
def test_cannot_drift_from_a_blocked_joint(leak_time_s):
    """A joint held still while the plan keeps accelerating it: the error stays bounded."""
    ref = JointReference(3, max_position_error_rad=0.05, max_velocity_error_rad_s=1.0,
                         leak_time_s=leak_time_s)
    q, dq = np.array([0.1, -0.2, 0.3]), np.zeros(3)
    ref.reset(q, dq)
    worst_q, worst_v = 0.0, 0.0
    for k in range(20_000):  # 20 s of a plan at 50 rad/s^2 that never happens
        ref.advance(q, dq, np.array([50.0, -50.0, 50.0 * np.sin(k * DT)]), DT)
        worst_q = max(worst_q, np.abs(ref.q_des - q).max())
        worst_v = max(worst_v, np.abs(ref.dq_des - dq).max())
    assert worst_q <= 0.05 + 1e-12 and worst_v <= 1.0 + 1e-12
    assert worst_q == pytest.approx(0.05)  # it does push as far as it may


def test_decays_to_the_measured_state_without_a_plan():
    ref = JointReference(1, max_position_error_rad=0.05, max_velocity_error_rad_s=1.0,
                         leak_time_s=0.2)
    ref.reset(np.array([0.04]), np.array([0.5]))
    q, dq = np.zeros(1), np.zeros(1)
    for _ in range(2000):  # 10 time constants
        ref.advance(q, dq, np.zeros(1), DT)
    assert abs(ref.q_des[0]) < 1e-3 and abs(ref.dq_des[0]) < 1e-4


def test_release_restarts_from_the_measured_state():
    ref = JointReference(1, max_position_error_rad=0.05, max_velocity_error_rad_s=1.0)
    ref.reset(np.array([0.0]), np.array([0.0]))
    for _ in range(100):
        ref.advance(np.zeros(1), np.zeros(1), np.array([100.0]), DT)
    ref.release()
    ref.advance(np.array([1.0]), np.array([0.0]), np.zeros(1), DT)
    assert ref.q_des[0] == pytest.approx(1.0) and ref.dq_des[0] == pytest.approx(0.0)


def test_bad_bounds_name_the_field():
    with pytest.raises(ConfigurationError,
                       match=r"max_position_error_rad: expected a value in \[0"):
        JointReference(2, max_position_error_rad=-0.1, max_velocity_error_rad_s=1.0)
