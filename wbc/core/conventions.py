"""The one conversion between Pinocchio's and MuJoCo's free-flyer conventions.

Pinocchio: ``q = [p_world (3), quat (x, y, z, w), joints]``, ``v = [linear velocity in the
base frame, angular velocity in the base frame, joint velocities]``.
MuJoCo free joint: ``qpos = [p_world (3), quat (w, x, y, z), joints]``, ``qvel = [linear
velocity in the world frame, angular velocity in the body frame, joint velocities]``.
Joint order is not touched here: both sides are in the description order.
"""

from __future__ import annotations

import numpy as np

from wbc.core.validation import as_vector

NQ, NV = 19, 18
#: Gravity [m/s^2], Pinocchio's default: what an accelerometer at rest reads, upwards.
GRAVITY_M_S2 = 9.81


def reorder_quaternion(quat: np.ndarray, *, to: str) -> np.ndarray:
    """Convert a quaternion between ``"xyzw"`` (Pinocchio) and ``"wxyz"`` (MuJoCo) order."""
    if to == "wxyz":
        return np.array([quat[3], quat[0], quat[1], quat[2]])
    if to == "xyzw":
        return np.array([quat[1], quat[2], quat[3], quat[0]])
    raise ValueError(f"to: expected 'xyzw' or 'wxyz', received {to!r}")


def _rotation_from_xyzw(quat: np.ndarray) -> np.ndarray:
    x, y, z, w = quat / np.linalg.norm(quat)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def pin_to_mujoco(q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio ``(q, v)`` -> MuJoCo ``(qpos, qvel)``."""
    q = as_vector("q", q, NQ)
    v = as_vector("v", v, NV)
    qpos = q.copy()
    qpos[3:7] = reorder_quaternion(q[3:7], to="wxyz")
    qvel = v.copy()
    qvel[0:3] = _rotation_from_xyzw(q[3:7]) @ v[0:3]
    return qpos, qvel


def mujoco_to_pin(qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo ``(qpos, qvel)`` -> Pinocchio ``(q, v)``."""
    qpos = as_vector("qpos", qpos, NQ)
    qvel = as_vector("qvel", qvel, NV)
    q = qpos.copy()
    q[3:7] = reorder_quaternion(qpos[3:7], to="xyzw")
    v = qvel.copy()
    v[0:3] = _rotation_from_xyzw(q[3:7]).T @ qvel[0:3]
    return q, v
