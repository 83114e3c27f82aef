"""Each leg's foot relative to the base from its three joint angles: compiled, no allocation.

What a state estimator needs from the legs, and nothing else: the foot sphere's centre in the
base frame, its Jacobian with respect to the leg's joints, and the foot's angular-velocity
Jacobian (for the rolling sphere). The chain is read from the Pinocchio model once (each
joint's placement in its parent and its principal axis); the tick's work is one compiled
call, about 1 us for the four legs. ``tests/test_leg_kinematics.py`` checks it against
Pinocchio at random configurations.
"""

from __future__ import annotations

import numba
import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.model.description import FOOT_FRAMES, LEGS, Go2Description

_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}
_F8 = numba.float64


@numba.njit(numba.void(_F8[::1], _F8[:, :, :, ::1], _F8[:, :, ::1], numba.int64[:, ::1],
                       _F8[:, ::1], _F8[:, ::1], _F8[:, :, ::1], _F8[:, :, ::1],
                       _F8[:, :, ::1]),
            cache=True, fastmath=False)
def leg_kinematics(joint_q, rotations, translations, axes, foot_offsets, foot_position,
                   foot_jacobian, foot_angular_jacobian, work):  # pragma: no cover - compiled
    """Foot centres, their Jacobians and angular Jacobians, base frame, all four legs.

    Args:
        joint_q: Joint angles [rad] (12,), description order (leg by leg, 3 joints each).
        rotations: Each joint's rotation in its parent's frame at zero angle (4, 3, 3, 3).
        translations: Each joint's origin in its parent's frame [m] (4, 3, 3).
        axes: Each joint's principal axis, 0 (x), 1 (y) or 2 (z) (4, 3).
        foot_offsets: The foot frame's origin in the last joint's frame [m] (4, 3).
        foot_position: Out: foot centres in the base frame [m] (4, 3).
        foot_jacobian: Out: ``d foot_position / d q_leg`` (4, 3, 3): column k is joint k.
        foot_angular_jacobian: Out: the foot's angular velocity in the base frame per joint
            velocity (4, 3, 3): column k is joint k's axis.
        work: Scratch space (4, 3, 3): nothing is allocated.
    """
    rotation, turned, origins = work[0], work[1], work[2]
    position = work[3, 0]
    for leg in range(4):
        for r in range(3):
            position[r] = 0.0
            for c in range(3):
                rotation[r, c] = 1.0 if r == c else 0.0
        for k in range(3):
            # Origin of joint k: parent origin + R_parent t_k.
            t = translations[leg, k]
            for r in range(3):
                position[r] += (rotation[r, 0] * t[0] + rotation[r, 1] * t[1]
                                + rotation[r, 2] * t[2])
                origins[k, r] = position[r]
            # R <- R R_k Rot(axis_k, q_k).
            rk = rotations[leg, k]
            for r in range(3):
                for c in range(3):
                    turned[r, c] = (rotation[r, 0] * rk[0, c] + rotation[r, 1] * rk[1, c]
                                    + rotation[r, 2] * rk[2, c])
            axis = axes[leg, k]
            a = (axis + 1) % 3
            b = (axis + 2) % 3
            cos = np.cos(joint_q[3 * leg + k])
            sin = np.sin(joint_q[3 * leg + k])
            for r in range(3):
                ca, cb = turned[r, a], turned[r, b]
                rotation[r, axis] = turned[r, axis]
                rotation[r, a] = ca * cos + cb * sin
                rotation[r, b] = cb * cos - ca * sin
            for r in range(3):
                foot_angular_jacobian[leg, r, k] = rotation[r, axis]
        offset = foot_offsets[leg]
        for r in range(3):
            foot_position[leg, r] = position[r] + (rotation[r, 0] * offset[0]
                                                   + rotation[r, 1] * offset[1]
                                                   + rotation[r, 2] * offset[2])
        for k in range(3):  # column k: axis_k x (foot - origin_k)
            ax = foot_angular_jacobian[leg, 0, k]
            ay = foot_angular_jacobian[leg, 1, k]
            az = foot_angular_jacobian[leg, 2, k]
            dx = foot_position[leg, 0] - origins[k, 0]
            dy = foot_position[leg, 1] - origins[k, 1]
            dz = foot_position[leg, 2] - origins[k, 2]
            foot_jacobian[leg, 0, k] = ay * dz - az * dy
            foot_jacobian[leg, 1, k] = az * dx - ax * dz
            foot_jacobian[leg, 2, k] = ax * dy - ay * dx


class LegKinematics:
    """The four legs' chains, read from the model once; :meth:`compute` fills the outputs.

    Attributes (updated in place by :meth:`update`, ``LEGS`` order):
        foot_position: Foot sphere centres in the base frame [m] (4, 3).
        foot_jacobian: Their Jacobians with respect to each leg's joints [m/rad] (4, 3, 3).
        foot_angular_jacobian: The feet's angular velocity per joint velocity, base frame
            (4, 3, 3).
        imu_offset: The ``imu`` frame's origin in the base frame [m] (3,), when the model
            has one (the GO2 URDF's is at (-0.02557, 0, 0.04232)).

    Example:
        >>> legs = LegKinematics()
        >>> legs.compute(q[7:])
        >>> legs.foot_position[1]       # FR foot centre, base frame
    """

    def __init__(self, description: Go2Description | None = None):
        description = description or Go2Description.default()
        model = description.model
        self.rotations = np.zeros((4, 3, 3, 3))
        self.translations = np.zeros((4, 3, 3))
        self.axes = np.zeros((4, 3), dtype=np.int64)
        self.foot_offsets = np.zeros((4, 3))
        for leg_index, leg in enumerate(LEGS):
            frame = model.frames[model.getFrameId(FOOT_FRAMES[leg])]
            chain = []
            joint = frame.parentJoint
            while joint > 1:  # up to the free flyer
                chain.append(joint)
                joint = model.parents[joint]
            chain.reverse()
            if len(chain) != 3:
                raise ConfigurationError(
                    f"{leg}: expected a chain of 3 joints from the base to {FOOT_FRAMES[leg]}, "
                    f"found {[model.names[j] for j in chain]}")
            for k, joint in enumerate(chain):
                kind = model.joints[joint].shortname()
                if kind not in _AXES:
                    raise ConfigurationError(
                        f"{model.names[joint]}: expected a revolute joint about a principal "
                        f"axis ({', '.join(_AXES)}), found {kind}")
                placement = model.jointPlacements[joint]
                self.rotations[leg_index, k] = placement.rotation
                self.translations[leg_index, k] = placement.translation
                self.axes[leg_index, k] = _AXES[kind]
            self.foot_offsets[leg_index] = frame.placement.translation
        self.imu_offset = np.zeros(3)
        if model.existFrame("imu"):
            imu = model.frames[model.getFrameId("imu")]
            if imu.parentJoint == 1:
                self.imu_offset[:] = imu.placement.translation
        self.foot_position = np.zeros((4, 3))
        self.foot_jacobian = np.zeros((4, 3, 3))
        self.foot_angular_jacobian = np.zeros((4, 3, 3))
        #: Scratch space of the compiled call.
        self.work = np.zeros((4, 3, 3))

    def compute(self, joint_q: np.ndarray) -> None:
        """Fill the outputs for joint angles ``joint_q`` [rad] (12,), description order."""
        leg_kinematics(np.ascontiguousarray(joint_q, dtype=np.float64), self.rotations,
                       self.translations, self.axes, self.foot_offsets, self.foot_position,
                       self.foot_jacobian, self.foot_angular_jacobian, self.work)
