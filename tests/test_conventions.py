"""Pinocchio <-> MuJoCo state conversion: round trips and agreement with both libraries."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from tests.conftest import random_configuration
from wbc.core.conventions import mujoco_to_pin, pin_to_mujoco, reorder_quaternion
from wbc.core.errors import ConfigurationError, NonFiniteError


def test_quaternion_order():
    xyzw = np.array([0.1, 0.2, 0.3, 0.9])
    np.testing.assert_array_equal(reorder_quaternion(xyzw, to="wxyz"), [0.9, 0.1, 0.2, 0.3])
    wxyz = reorder_quaternion(xyzw, to="wxyz")
    np.testing.assert_array_equal(reorder_quaternion(wxyz, to="xyzw"), xyzw)


def test_round_trip_random_states(model):
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = random_configuration(model, rng, scale=1.0)
        v = rng.normal(size=18)
        q2, v2 = mujoco_to_pin(*pin_to_mujoco(q, v))
        np.testing.assert_allclose(q2, q, atol=1e-12)
        np.testing.assert_allclose(v2, v, atol=1e-12)


def test_velocity_frames_match_integration(model):
    """Integrating each side's velocity in its own convention gives the same new pose."""
    from sim.scene import build_go2_spec

    mj_model = build_go2_spec().compile()
    rng = np.random.default_rng(1)
    dt = 1e-6
    for _ in range(5):
        q = random_configuration(model, rng, scale=1.0)
        v = rng.normal(size=18)
        qpos, qvel = pin_to_mujoco(q, v)
        qpos_next = qpos.copy()
        mujoco.mj_integratePos(mj_model, qpos_next, qvel, dt)
        q_next = pin.integrate(model, q, v * dt)
        np.testing.assert_allclose(mujoco_to_pin(qpos_next, qvel)[0], q_next, atol=1e-12)


def test_bad_shapes_and_values():
    with pytest.raises(ConfigurationError,
                       match=r"q: expected an array of shape \(19,\), received shape \(18,\)"):
        pin_to_mujoco(np.zeros(18), np.zeros(18))
    q = np.zeros(19)
    q[6] = 1.0
    v = np.zeros(18)
    v[3] = np.nan
    with pytest.raises(NonFiniteError, match="v: non-finite value at index \\[3\\]"):
        pin_to_mujoco(q, v)
