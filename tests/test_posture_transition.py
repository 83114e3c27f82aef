"""PostureTransition: the pose's geometry, computed once and never shared mutably."""

import numpy as np
import pinocchio as pin

from wbc import WholeBodyController
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS
from wbc.motions.posture_transition import PostureTransition


def test_transition_uses_the_controllers_description_and_the_poses_geometry(description):
    controller = WholeBodyController(description=description)
    transition = PostureTransition(controller, "lying")
    assert transition.description is controller.description
    model, data = description.model, description.model.createData()
    q = description.pose("lying")
    pin.framesForwardKinematics(model, data, q)
    feet = np.array([data.oMf[model.getFrameId(FOOT_FRAMES[leg])].translation for leg in LEGS])
    com = pin.centerOfMass(model, data, q)
    np.testing.assert_allclose(transition.com_offset[2], com[2] - feet[:, 2].min() + FOOT_RADIUS_M,
                               atol=1e-12)
    np.testing.assert_allclose(transition.com_offset[:2], com[:2] - feet[:, :2].mean(axis=0),
                               atol=1e-12)


def test_each_transition_has_its_own_arrays(description):
    controller = WholeBodyController(description=description)
    first, second = (PostureTransition(controller, "standing") for _ in range(2))
    offset, under = second.com_offset.copy(), second.foot_under_shoulder["FR"].copy()
    assert np.all(np.abs(under) > 1e-3) and offset[2] > 0.2
    first.com_offset[:] = 0.0
    first.foot_under_shoulder["FR"][:] = 0.0
    third = PostureTransition(controller, "standing")
    for transition in (second, third):
        np.testing.assert_array_equal(transition.com_offset, offset)
        np.testing.assert_array_equal(transition.foot_under_shoulder["FR"], under)
