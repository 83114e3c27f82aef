"""Compiled quaternion arithmetic for the estimator and the simulated IMU, scalar first.

Quaternions here are ``(w, x, y, z)`` (MuJoCo's and the GO2 IMU's order; Pinocchio's
``(x, y, z, w)`` is converted in :mod:`wbc.core.conventions` and where the estimator writes
``q``). Rotation vectors are axis times angle [rad]. ``tests/test_quaternion_kernels.py``
checks every function against Pinocchio's.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True)
def quat_multiply(a, b, out):  # pragma: no cover - compiled
    """``out = a * b`` (``out`` must not alias ``a`` or ``b``)."""
    out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3]
    out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2]
    out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1]
    out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]


@numba.njit(cache=True)
def quat_exp(rx, ry, rz, out):  # pragma: no cover - compiled
    """``out`` = the unit quaternion of the rotation vector ``(rx, ry, rz)`` [rad]."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    half = 0.5 * angle
    out[0] = math.cos(half)
    # sin(a/2)/a, with its series near zero (exact to rounding below 1e-4 rad).
    scale = math.sin(half) / angle if angle > 1e-4 else 0.5 - angle * angle / 48.0
    out[1] = rx * scale
    out[2] = ry * scale
    out[3] = rz * scale


@numba.njit(cache=True)
def quat_log(quat, out):  # pragma: no cover - compiled
    """``out`` = the rotation vector [rad] of the unit quaternion ``quat`` (angle <= pi)."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    if w < 0.0:  # the same rotation, the short way round
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    scale = 2.0 * math.atan2(s, w) / s if s > 1e-9 else 2.0 / w
    out[0] = x * scale
    out[1] = y * scale
    out[2] = z * scale


@numba.njit(cache=True)
def quat_normalize(quat):  # pragma: no cover - compiled
    """Scale ``quat`` to unit norm in place."""
    norm = math.sqrt(quat[0] ** 2 + quat[1] ** 2 + quat[2] ** 2 + quat[3] ** 2)
    for k in range(4):
        quat[k] /= norm


@numba.njit(cache=True)
def rotation_from_wxyz(w, x, y, z, out):  # pragma: no cover - compiled
    """``out`` (3, 3) = the rotation matrix of the quaternion ``(w, x, y, z)``, not normalised
    (Eigen's and so Pinocchio's: a non-unit quaternion gives what they give)."""
    out[0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[0, 1] = 2.0 * (x * y - z * w)
    out[0, 2] = 2.0 * (x * z + y * w)
    out[1, 0] = 2.0 * (x * y + z * w)
    out[1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[1, 2] = 2.0 * (y * z - x * w)
    out[2, 0] = 2.0 * (x * z - y * w)
    out[2, 1] = 2.0 * (y * z + x * w)
    out[2, 2] = 1.0 - 2.0 * (x * x + y * y)


@numba.njit(cache=True)
def quat_rotation(quat, out):  # pragma: no cover - compiled
    """``out`` (3, 3) = the rotation matrix of the unit quaternion ``quat``."""
    rotation_from_wxyz(quat[0], quat[1], quat[2], quat[3], out)


@numba.njit(cache=True)
def quat_yaw(quat):  # pragma: no cover - compiled
    """The yaw [rad] (rotation about world z, in ZYX angles) of the unit quaternion."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


@numba.njit(cache=True)
def rotate_inverse(quat, vector, out):  # pragma: no cover - compiled
    """``out = R(quat)^T vector`` (world to body) for a unit quaternion."""
    w, x, y, z = quat[0], quat[1], quat[2], quat[3]
    a, b, c = vector[0], vector[1], vector[2]
    out[0] = (1 - 2 * (y * y + z * z)) * a + 2 * (x * y + z * w) * b + 2 * (x * z - y * w) * c
    out[1] = 2 * (x * y - z * w) * a + (1 - 2 * (x * x + z * z)) * b + 2 * (y * z + x * w) * c
    out[2] = 2 * (x * z + y * w) * a + 2 * (y * z - x * w) * b + (1 - 2 * (x * x + y * y)) * c


def quat_wxyz_to_rotation(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix of a ``(w, x, y, z)`` quaternion (normalised first), in NumPy."""
    q = np.asarray(quat, dtype=float)
    out = np.empty((3, 3))
    quat_rotation(q / np.linalg.norm(q), out)
    return out
