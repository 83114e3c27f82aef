"""The GO2 description: names, order, poses, limits, and the error when files are missing."""

import importlib.metadata

import numpy as np
import pytest

from wbc.core.errors import DescriptionNotFoundError, UnknownNameError
from wbc.model import description as desc_module
from wbc.model.description import (
    FOOT_FRAMES,
    JOINT_NAMES,
    LEGS,
    UNITREE_SDK_JOINT_NAMES,
    Go2Description,
)


def test_joint_order_is_urdf_order(description):
    assert JOINT_NAMES[:3] == ("FL_hip_joint", "FL_thigh_joint", "FL_calf_joint")
    assert [n[:2] for n in JOINT_NAMES[::3]] == list(LEGS) == ["FL", "FR", "RL", "RR"]
    assert tuple(description.model.names[2:]) == JOINT_NAMES
    assert UNITREE_SDK_JOINT_NAMES[:3] == ("FR_hip_joint", "FR_thigh_joint", "FR_calf_joint")
    assert sorted(UNITREE_SDK_JOINT_NAMES) == sorted(JOINT_NAMES)


def test_files_found_from_distribution(description):
    assert description.urdf_path.is_file() and description.srdf_path.is_file()
    assert description.package_share_dir.name == "share"
    assert (description.package_share_dir / "example-robot-data" / "robots").is_dir()


def test_limits_from_urdf(description):
    np.testing.assert_allclose(description.effort_limit[:3], [23.7, 23.7, 45.43])
    np.testing.assert_allclose(description.velocity_limit[:3], [30.1, 30.1, 15.7])
    np.testing.assert_allclose(description.position_lower[:3], [-1.0472, -1.5708, -2.7227])
    np.testing.assert_allclose(description.position_upper[6:9], [1.0472, 4.5379, -0.83776])
    assert description.total_mass == pytest.approx(16.085, abs=1e-6)


def test_standing_pose_from_srdf(description):
    q = description.pose("standing")
    np.testing.assert_allclose(q[:7], [0, 0, 0.335, 0, 0, 0, 1])
    np.testing.assert_allclose(q[7:10], [0.068, 0.785, -1.44])
    np.testing.assert_allclose(q[10:13], [-0.068, 0.785, -1.44])
    q[2] = 99.0  # a copy: the description is not changed
    assert description.pose("standing")[2] == 0.335


def test_lying_pose_inside_limits_with_feet_on_ground(description):
    import pinocchio as pin
    q = description.pose("lying")
    assert np.all(q[7:] >= description.position_lower)
    assert np.all(q[7:] <= description.position_upper)
    data = description.model.createData()
    pin.framesForwardKinematics(description.model, data, q)
    z = [data.oMf[description.model.getFrameId(f)].translation[2] for f in FOOT_FRAMES.values()]
    assert min(z) == pytest.approx(desc_module.FOOT_RADIUS_M, abs=1e-9)
    assert q[2] < 0.15


def test_unknown_pose_lists_valid_names(description):
    with pytest.raises(UnknownNameError,
                       match="unknown pose 'sitting'; valid poses: standing, lying"):
        description.pose("sitting")


def test_unknown_joint_lists_valid_names(description):
    with pytest.raises(UnknownNameError) as info:
        description.joint_index("FR_knee_joint")
    assert "FR_knee_joint" in str(info.value)
    for name in JOINT_NAMES:
        assert name in str(info.value)


def test_missing_distribution_says_what_to_install(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(desc_module.importlib.metadata, "distribution", missing)
    desc_module._installed_go2_folder.cache_clear()  # found once a process: look again
    with pytest.raises(DescriptionNotFoundError, match="pip install example-robot-data==6.0.0"):
        Go2Description()
    with pytest.raises(DescriptionNotFoundError):  # a failure is not cached
        Go2Description()


def test_distribution_without_go2_files(monkeypatch):
    class Empty:
        version = "0.0"
        files = ()

    monkeypatch.setattr(desc_module.importlib.metadata, "distribution", lambda name: Empty())
    desc_module._installed_go2_folder.cache_clear()
    with pytest.raises(DescriptionNotFoundError, match="has no .*go2.urdf"):
        Go2Description()


def test_folder_is_found_once_a_process(monkeypatch):
    desc_module._installed_go2_folder.cache_clear()
    folder = Go2Description().folder

    def scanned_again(name):
        raise AssertionError("the distribution was scanned again")

    monkeypatch.setattr(desc_module.importlib.metadata, "distribution", scanned_again)
    assert Go2Description().folder == folder


def test_default_is_one_description_a_process():
    assert Go2Description.default() is Go2Description.default()
    assert Go2Description.default().model is Go2Description.default().model
