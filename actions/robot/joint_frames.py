"""Each leg joint's parent-to-child transform from the URDF and the joint angles:
:class:`JointFrames` (what a 3D view needs to draw the robot's links).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES


def _rpy_quaternion(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """The URDF's fixed-axis roll-pitch-yaw [rad] as a quaternion ``(x, y, z, w)``."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy])


class JointFrames:
    """The transforms ``T_parent_child`` of the 12 leg joints (:data:`JOINT_NAMES` order),
    read once from the URDF: the joint's origin, then its rotation about its axis.

    Args:
        urdf_path: The robot's URDF.

    Raises:
        ConfigurationError: A leg joint missing from the URDF, or one that is not revolute.
    """

    def __init__(self, urdf_path: Path | str):
        root = ET.parse(urdf_path).getroot()
        joints = {j.get("name"): j for j in root.iter("joint")}
        missing = [name for name in JOINT_NAMES if name not in joints]
        if missing:
            raise ConfigurationError(f"urdf {urdf_path}: no joint {', '.join(missing)}; "
                                     f"expected the GO2's {', '.join(JOINT_NAMES)}")
        self.parents: list[str] = []
        self.children: list[str] = []
        n = len(JOINT_NAMES)
        #: Each joint's origin translation [m] (12, 3), origin rotation (12, 4: x, y, z, w)
        #: and unit axis (12, 3) in the origin's frame.
        self.origin_xyz, self.origin_quat, self.axis = (np.zeros((n, 3)), np.zeros((n, 4)),
                                                        np.zeros((n, 3)))
        for k, name in enumerate(JOINT_NAMES):
            joint = joints[name]
            if joint.get("type") != "revolute":
                raise ConfigurationError(f"urdf {urdf_path}: joint {name} is "
                                         f"{joint.get('type')!r}; expected 'revolute'")
            origin = joint.find("origin")
            xyz = (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()
            rpy = (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()
            axis_el = joint.find("axis")
            axis = np.array([float(a) for a in (axis_el.get("xyz", "1 0 0").split()
                                                if axis_el is not None else (1, 0, 0))])
            self.origin_xyz[k] = [float(x) for x in xyz]
            self.origin_quat[k] = _rpy_quaternion(*(float(r) for r in rpy))
            self.axis[k] = axis / np.linalg.norm(axis)
            self.parents.append(str(joint.find("parent").get("link")))  # type: ignore[union-attr]
            self.children.append(str(joint.find("child").get("link")))  # type: ignore[union-attr]

    def rotations(self, angles_rad: np.ndarray) -> np.ndarray:
        """``T_parent_child``'s rotation for each joint at ``angles_rad`` (12,) [rad], as
        quaternions ``(x, y, z, w)`` (12, 4): the origin's rotation times the joint's."""
        half = 0.5 * np.asarray(angles_rad, dtype=float)
        b = np.concatenate([self.axis * np.sin(half)[:, None], np.cos(half)[:, None]], axis=1)
        a = self.origin_quat
        ax, ay, az, aw = a[:, 0], a[:, 1], a[:, 2], a[:, 3]
        bx, by, bz, bw = b[:, 0], b[:, 1], b[:, 2], b[:, 3]
        return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                         aw * by - ax * bz + ay * bw + az * bx,
                         aw * bz + ax * by - ay * bx + az * bw,
                         aw * bw - ax * bx - ay * by - az * bz], axis=1)
