"""Compiled per-kind task kernels: each fills a task's arrays in one call, without allocation."""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def log3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix (the inverse of Rodrigues' formula)."""
    cos = min(1.0, max(-1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    # atan2 stays accurate near 0 and pi, where arccos of the trace does not.
    angle = np.arctan2(0.5 * np.sqrt(w @ w), cos)
    if angle < 1e-6:
        return 0.5 * w
    if np.pi - angle < 1e-6:  # at pi the antisymmetric part vanishes: use the symmetric
        axis = np.sqrt(np.maximum(0.0, (np.diag(R) - cos) / (1.0 - cos)))
        k = np.argmax(axis)
        for i in range(3):
            if i != k:
                axis[i] = np.copysign(axis[i], R[k, i] + R[i, k])
        if axis @ w < 0.0:  # what is left of the antisymmetric part gives the sign
            axis = -axis
        return angle * axis / np.linalg.norm(axis)
    return angle / (2.0 * np.sin(angle)) * w


@numba.njit(cache=True)
def _point_rows(J, position, velocity, acceleration, axes, reference, gains,
                jacobian, drift, error, error_rate, desired):
    """Rows ``axes`` of a point's position task, from its Jacobian, velocity and drift."""
    kp, kd = gains[0], gains[1]
    for r in range(axes.size):
        a = axes[r]
        jacobian[r, :] = J[a, :]
        drift[r] = acceleration[a]
        error[r] = reference[0, r] - position[a]
        error_rate[r] = reference[1, r] - velocity[a]
        desired[r] = kp * error[r] + kd * error_rate[r] + reference[2, r]


@numba.njit(cache=True)
def com_task(com_jacobian, com_position, com_velocity, com_drift, axes, reference, gains,
             jacobian, drift, error, error_rate, desired):
    """The centre-of-mass task's arrays, on the world axes ``axes``."""
    _point_rows(com_jacobian, com_position, com_velocity, com_drift, axes, reference, gains,
                jacobian, drift, error, error_rate, desired)


@numba.njit(cache=True)
def frame_position_task(frame_jacobian, frame_position, frame_velocity, frame_drift, index,
                        axes, reference, gains, jacobian, drift, error, error_rate, desired):
    """A frame origin's position task (world axes ``axes``), frame ``index`` of the kinematics."""
    _point_rows(frame_jacobian[index], frame_position[index], frame_velocity[index],
                frame_drift[index], axes, reference, gains, jacobian, drift, error,
                error_rate, desired)


@numba.njit(cache=True)
def base_orientation_task(base_rotation, v, rotation_target, reference, bias, gains, error,
                          error_rate, desired):
    """Base orientation error (base frame) and desired angular acceleration.

    The Jacobian (a selection of ``v[3:6]``) and the zero drift are constant.
    """
    err = log3(base_rotation.T @ rotation_target)
    kp, kd = gains[0], gains[1]
    for k in range(3):
        error[k] = err[k]
        error_rate[k] = reference[1, k] - v[3 + k]
        desired[k] = kp * err[k] + kd * error_rate[k] + reference[2, k] + bias[k]


@numba.njit(cache=True)
def posture_task(q, v, reference, gains, error, error_rate, desired):
    """Joint posture errors and desired joint accelerations (selection Jacobian, no drift)."""
    kp, kd = gains[0], gains[1]
    n = error.size
    for k in range(n):
        error[k] = reference[0, k] - q[q.size - n + k]
        error_rate[k] = reference[1, k] - v[v.size - n + k]
        desired[k] = kp * error[k] + kd * error_rate[k] + reference[2, k]


@numba.njit(cache=True)
def rolling_contacts(frame_jacobian, frame_drift, indices, radius, gains, v, jacobian, drift,
                     error_rate, desired):
    """Rolling-sphere contact points' Jacobians, drifts, minus their velocities, and the
    desired accelerations ``kd * error_rate`` (``kd = gains[1]``; 3 rows each).

    The contact point sits ``d = (0, 0, -radius)`` below the sphere centre (world), so
    ``J = J_lin - [d]x J_ang`` and ``drift = a_lin - [d]x alpha``.
    """
    nv = v.size
    for i in range(indices.size):
        J = frame_jacobian[indices[i]]
        acc = frame_drift[indices[i]]
        row = 3 * i
        for k in range(nv):
            jacobian[row, k] = J[0, k] - radius * J[4, k]
            jacobian[row + 1, k] = J[1, k] + radius * J[3, k]
            jacobian[row + 2, k] = J[2, k]
        drift[row] = acc[0] - radius * acc[4]
        drift[row + 1] = acc[1] + radius * acc[3]
        drift[row + 2] = acc[2]
        for a in range(3):
            s = 0.0
            for k in range(nv):
                s += jacobian[row + a, k] * v[k]
            error_rate[row + a] = -s
            desired[row + a] = -gains[1] * s


@numba.njit(cache=True)
def force_target(reference, desired):
    """A contact force task's desired value: its target force [N] plus the feed-forward row."""
    for k in range(desired.size):
        desired[k] = reference[0, k] + reference[2, k]
