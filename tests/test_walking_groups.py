"""The walking kernel's address record: the arrays it reads and writes, checked before their
addresses are taken."""

import numpy as np
import pytest

from wbc.core.errors import ConfigurationError
from wbc.locomotion.walking_groups import Measured, Targets, address_record


def groups(**changes):
    measured = Measured(np.zeros(3), np.zeros(3), np.eye(3), np.zeros(3), np.zeros(18),
                        np.zeros((8, 3)))
    targets = Targets(np.zeros((3, 3)), np.eye(3), np.zeros((3, 3)),
                      tuple(np.zeros((3, 3)) for _ in range(4)))
    return (measured._replace(**{k: v for k, v in changes.items() if k in Measured._fields}),
            targets._replace(**{k: v for k, v in changes.items() if k in Targets._fields}))


def test_the_record_holds_each_arrays_address():
    measured, targets = groups()
    entry = address_record(measured, targets)[0]
    assert entry["com_position"] == measured.com_position.ctypes.data
    assert entry["feet_position"] == measured.frame_position.ctypes.data
    assert entry["base_velocity"] == measured.v.ctypes.data
    assert entry["foot_references"].tolist() == [f.ctypes.data for f in targets.feet]


@pytest.mark.parametrize(("change", "message"), [
    ({"com_velocity": np.zeros(3, dtype=np.float32)},
     (r"Measured.com_velocity: expected a C-contiguous float64 array of shape \(3,\), "
     r"received float32 \(3,\)")),
    ({"base_rotation": np.zeros((3, 6))[:, ::2]},
     r"Measured.base_rotation: expected a C-contiguous float64 array of shape \(3, 3\)"),
    ({"frame_position": np.zeros((3, 3))},
     r"Measured.frame_position: .* shape \(4, 3\), received float64 \(3, 3\)"),
    ({"feet": (np.zeros((3, 3)),) * 3 + (np.zeros((3, 3)).T,)},  # transposed: F order
     (r"Targets.feet\[3\]: expected a C-contiguous float64 array of shape \(3, 3\) that can "
     r"be written")),
])
def test_an_array_the_kernel_cannot_use_is_refused_naming_it(change, message):
    measured, targets = groups(**change)
    with pytest.raises(ConfigurationError, match=message):
        address_record(measured, targets)


def test_a_read_only_target_is_refused():
    com = np.zeros((3, 3))
    com.flags.writeable = False
    measured, targets = groups(com=com)
    with pytest.raises(ConfigurationError, match=r"Targets.com: .* that can be written"):
        address_record(measured, targets)
    read_only = np.zeros(3)
    read_only.flags.writeable = False  # the kernel only reads the kinematics
    address_record(*groups(com_position=read_only))
