"""The compiled leg kinematics against Pinocchio at random configurations."""

import numpy as np
import pinocchio as pin
import pytest

from tests.conftest import random_configuration
from wbc.model.description import FOOT_FRAMES, LEGS
from wbc.model.leg_kinematics import LegKinematics


@pytest.fixture(scope="module")
def legs():
    return LegKinematics()


def test_foot_positions_and_jacobians_match_pinocchio(legs, model):
    data = model.createData()
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = random_configuration(model, rng, scale=1.0)
        q[:3] = 0.0
        q[3:7] = [0.0, 0.0, 0.0, 1.0]  # base at the origin: world = base frame
        pin.computeJointJacobians(model, data, q)
        pin.framesForwardKinematics(model, data, q)
        legs.compute(q[7:])
        for i, leg in enumerate(LEGS):
            frame = model.getFrameId(FOOT_FRAMES[leg])
            np.testing.assert_allclose(legs.foot_position[i], data.oMf[frame].translation,
                                       atol=1e-12)
            jacobian = pin.getFrameJacobian(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            columns = slice(6 + 3 * i, 9 + 3 * i)
            np.testing.assert_allclose(legs.foot_jacobian[i], jacobian[:3, columns], atol=1e-12)
            np.testing.assert_allclose(legs.foot_angular_jacobian[i], jacobian[3:, columns],
                                       atol=1e-12)
            # The rest of the leg's columns are zero: each foot depends on its own leg only.
            others = np.delete(jacobian[:3, 6:], np.arange(3 * i, 3 * i + 3), axis=1)
            assert np.all(others == 0.0)


def test_imu_offset_is_the_urdf_imu_frame(legs):
    np.testing.assert_allclose(legs.imu_offset, [-0.02557, 0.0, 0.04232])


def test_update_accepts_strided_joint_angles(legs, model):
    q = np.ascontiguousarray(random_configuration(model, np.random.default_rng(1)))
    legs.compute(q[7:])
    expected = legs.foot_position.copy()
    wide = np.zeros(24)
    wide[::2] = q[7:]
    legs.compute(wide[::2])
    np.testing.assert_array_equal(legs.foot_position, expected)
