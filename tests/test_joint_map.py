"""Joint order mapping by name."""

import numpy as np
import pytest

from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.model.description import JOINT_NAMES, UNITREE_SDK_JOINT_NAMES
from wbc.model.joint_map import JointMap


def test_unitree_sdk_order_by_name():
    sdk = JointMap.unitree_sdk()
    values = np.arange(12.0)  # description order: value i belongs to JOINT_NAMES[i]
    other = sdk.to_other(values)
    for i, name in enumerate(UNITREE_SDK_JOINT_NAMES):
        assert other[i] == JOINT_NAMES.index(name)
    np.testing.assert_array_equal(sdk.from_other(other), values)


def test_round_trip_random_order():
    rng = np.random.default_rng(3)
    names = list(rng.permutation(JOINT_NAMES))
    m = JointMap(names)
    x = rng.normal(size=12)
    np.testing.assert_array_equal(m.from_other(m.to_other(x)), x)
    np.testing.assert_array_equal(m.to_other(x)[names.index("RR_calf_joint")], x[11])


def test_aliases():
    names = [n.replace("_joint", "") for n in JOINT_NAMES]
    m = JointMap(names, aliases={n: f"{n}_joint" for n in names})
    np.testing.assert_array_equal(m.index, np.arange(12))


def test_unknown_name_lists_valid_ones():
    names = list(JOINT_NAMES)
    names[4] = "FR_knee_joint"
    with pytest.raises(UnknownNameError,
                       match="unknown joint 'FR_knee_joint'; valid joints: FL_hip_joint"):
        JointMap(names)


def test_duplicate_and_count_errors():
    with pytest.raises(ConfigurationError, match="duplicate joints \\['FL_hip_joint'\\]"):
        JointMap(["FL_hip_joint"] + list(JOINT_NAMES[:11]))
    with pytest.raises(ConfigurationError, match="expected 12 joint names, received 3"):
        JointMap(JOINT_NAMES[:3])


def test_wrong_shape_says_expected_shape():
    with pytest.raises(ConfigurationError,
                       match=r"expected an array of shape \(12,\), received shape \(11,\)"):
        JointMap.unitree_sdk().to_other(np.zeros(11))
