"""PlaCo imports and loads the same GO2 as Pinocchio."""

import numpy as np
import pinocchio as pin
import pytest

from wbc.model.description import FOOT_FRAMES, JOINT_NAMES


def test_placo_loads_the_same_go2(description, model):
    import placo

    description.set_ros_package_path()
    robot = placo.RobotWrapper(str(description.urdf_path), placo.Flags.ignore_collisions)
    assert list(robot.joint_names()) == list(JOINT_NAMES)
    assert robot.total_mass() == pytest.approx(description.total_mass, rel=1e-6)
    q = description.pose("standing")
    robot.state.q = q
    robot.update_kinematics()
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    for frame in FOOT_FRAMES.values():
        p_placo = robot.get_T_world_frame(frame)[:3, 3]
        p_pin = data.oMf[model.getFrameId(frame)].translation
        np.testing.assert_allclose(p_placo, p_pin, atol=1e-9)
