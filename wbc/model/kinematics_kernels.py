"""RobotKinematics' compiled algorithms: placements, Jacobians, dynamics and CoM in one call.

Every function reads the constant model record ``m`` and writes the data record ``d`` that
:func:`wbc.model.kinematics_records.kinematics_records` lays out; :func:`_update` runs them
all. Nothing allocates.
"""

from __future__ import annotations

import numba
import numpy as np

from wbc.core.quaternion_kernels import rotation_from_wxyz

# Joint kinds in ``model.kind``: index 0 is Pinocchio's universe, which never moves.
_UNIVERSE, _FREE_FLYER, _REVOLUTE = 0, 1, 2
# What the compiled update returns.
_DONE, _NOT_FINITE, _WRONG_SIZE = 0, 1, 2


# --- 3D and spatial-vector helpers. Spatial vectors are 6-vectors (linear; angular), in
# world coordinates and taken at the world origin, like Pinocchio's data.ov / data.oa.


@numba.njit(cache=True)
def _cross(a, b, out):
    """``out = a x b`` (3-vectors)."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@numba.njit(cache=True)
def _matmul3(a, b, out):
    """``out = a @ b`` (3x3; ``out`` must not alias ``a`` or ``b``)."""
    for r in range(3):
        for c in range(3):
            out[r, c] = a[r, 0] * b[0, c] + a[r, 1] * b[1, c] + a[r, 2] * b[2, c]


@numba.njit(cache=True)
def _transform_point(rotation, translation, point, out):
    """``out = translation + rotation @ point``."""
    for r in range(3):
        out[r] = (translation[r] + rotation[r, 0] * point[0] + rotation[r, 1] * point[1]
                  + rotation[r, 2] * point[2])


@numba.njit(cache=True)
def _dot6(a, b):
    """Pairing of a motion and a force (power), or plain dot product of 6-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]


@numba.njit(cache=True)
def _motion_cross(m1, m2, out):
    """``out = m1 x m2`` (spatial motion cross product)."""
    out[0] = m1[4] * m2[2] - m1[5] * m2[1] + m1[1] * m2[5] - m1[2] * m2[4]
    out[1] = m1[5] * m2[0] - m1[3] * m2[2] + m1[2] * m2[3] - m1[0] * m2[5]
    out[2] = m1[3] * m2[1] - m1[4] * m2[0] + m1[0] * m2[4] - m1[1] * m2[3]
    out[3] = m1[4] * m2[5] - m1[5] * m2[4]
    out[4] = m1[5] * m2[3] - m1[3] * m2[5]
    out[5] = m1[3] * m2[4] - m1[4] * m2[3]


@numba.njit(cache=True)
def _add_force_cross(m, f, out):
    """``out += m x* f`` (spatial force cross product: the rate of change of a moving momentum)."""
    out[0] += m[4] * f[2] - m[5] * f[1]
    out[1] += m[5] * f[0] - m[3] * f[2]
    out[2] += m[3] * f[1] - m[4] * f[0]
    out[3] += m[4] * f[5] - m[5] * f[4] + m[1] * f[2] - m[2] * f[1]
    out[4] += m[5] * f[3] - m[3] * f[5] + m[2] * f[0] - m[0] * f[2]
    out[5] += m[3] * f[4] - m[4] * f[3] + m[0] * f[1] - m[1] * f[0]


@numba.njit(cache=True)
def _apply_inertia(mass, first_moment, inertia, motion, out):
    """``out = I motion``: the momentum of a spatial inertia moving with ``motion``.

    Args:
        mass: Mass [kg].
        first_moment: ``mass * com`` [kg m], the CoM in world coordinates.
        inertia: Rotational inertia about the world origin [kg m^2].
        motion: Spatial velocity at the origin (linear [m/s]; angular [rad/s]).
        out: Linear momentum [kg m/s]; angular momentum about the origin [kg m^2/s].
    """
    v0, v1, v2, w0, w1, w2 = motion[0], motion[1], motion[2], motion[3], motion[4], motion[5]
    h0, h1, h2 = first_moment[0], first_moment[1], first_moment[2]
    out[0] = mass * v0 + w1 * h2 - w2 * h1
    out[1] = mass * v1 + w2 * h0 - w0 * h2
    out[2] = mass * v2 + w0 * h1 - w1 * h0
    out[3] = h1 * v2 - h2 * v1 + inertia[0, 0] * w0 + inertia[0, 1] * w1 + inertia[0, 2] * w2
    out[4] = h2 * v0 - h0 * v2 + inertia[1, 0] * w0 + inertia[1, 1] * w1 + inertia[1, 2] * w2
    out[5] = h0 * v1 - h1 * v0 + inertia[2, 0] * w0 + inertia[2, 1] * w1 + inertia[2, 2] * w2


@numba.njit(cache=True)
def _axis_rotation(axis, angle, out):
    """Rotation by ``angle`` [rad] about the unit ``axis`` (Rodrigues' formula)."""
    c, s = np.cos(angle), np.sin(angle)
    for r in range(3):
        for k in range(3):
            out[r, k] = (1.0 - c) * axis[r] * axis[k]
        out[r, r] += c
    out[1, 2] -= s * axis[0]
    out[2, 1] += s * axis[0]
    out[2, 0] -= s * axis[1]
    out[0, 2] += s * axis[1]
    out[0, 1] -= s * axis[2]
    out[1, 0] += s * axis[2]


# --- The algorithms. ``m`` is the constant model record, ``d`` the data record (outputs and
# scratch); see kinematics_records for their fields.


@numba.njit(cache=True)
def _forward_pass(q, v, m, d):
    """Placements, motion axes, velocities, bias accelerations and body wrenches, root to leaves.

    Args:
        q: Configuration (nq,).
        v: Velocity (nv,).
        m: Model record (read).
        d: Data record. Fills ``joint_rotation/translation`` (world placements),
            ``motion_axes`` (each dof's unit motion in the world at the origin: the columns of
            the world Jacobian), ``velocity``, ``bias_acceleration`` (at zero ``qdd``, without
            gravity), the bodies' world inertias (``subtree_*``, summed later) and the
            Newton-Euler wrenches ``force = I (a - g) + v x* (I v)``.
    """
    rotation_before, rotation_joint = d.scratch_rotation[0], d.scratch_rotation[1]
    rotated_inertia = d.scratch_rotation[1]  # R I_c, once the joint rotation is used
    cross, momentum, point = d.scratch_motion[0], d.scratch_motion[1], d.scratch_point
    for i in range(1, m.parent.size):
        p = m.parent[i]
        rotation, translation = d.joint_rotation[i], d.joint_translation[i]
        # oMi = oMparent * jointPlacement * joint(q)
        _matmul3(d.joint_rotation[p], m.placement_rotation[i], rotation_before)
        _transform_point(d.joint_rotation[p], d.joint_translation[p],
                         m.placement_translation[i], translation)
        k = m.idx_v[i]
        if m.kind[i] == _FREE_FLYER:
            iq = m.idx_q[i]
            rotation_from_wxyz(q[iq + 6], q[iq + 3], q[iq + 4], q[iq + 5], rotation_joint)
            _transform_point(rotation_before, translation, q[iq:iq + 3], translation)
            _matmul3(rotation_before, rotation_joint, rotation)
            # Pinocchio's free-flyer velocity is in the base frame: the base axes, in the world.
            for c in range(3):
                linear, angular = d.motion_axes[k + c], d.motion_axes[k + 3 + c]
                for r in range(3):
                    linear[r], linear[3 + r] = rotation[r, c], 0.0
                    angular[3 + r] = rotation[r, c]
                _cross(translation, angular[3:], angular[:3])
        else:
            _axis_rotation(m.axis[i], q[m.idx_q[i]], rotation_joint)
            _matmul3(rotation_before, rotation_joint, rotation)
            axis = d.motion_axes[k]
            for r in range(3):
                axis[3 + r] = (rotation[r, 0] * m.axis[i, 0] + rotation[r, 1] * m.axis[i, 1]
                               + rotation[r, 2] * m.axis[i, 2])
            _cross(translation, axis[3:], axis[:3])  # a rotation about a line through it
        # v_i = v_p + S qd;  a_i = a_p + v_p x (S qd) at qdd = 0 (S moves with the parent).
        velocity, acceleration = d.velocity[i], d.bias_acceleration[i]
        velocity[:] = d.velocity[p]
        acceleration[:] = d.bias_acceleration[p]
        for c in range(k, k + m.nv_joint[i]):
            _motion_cross(d.velocity[p], d.motion_axes[c], cross)
            for r in range(6):
                velocity[r] += d.motion_axes[c, r] * v[c]
                acceleration[r] += cross[r] * v[c]
        # The body's inertia in the world, about the origin (parallel-axis theorem).
        mass, first_moment, inertia = m.mass[i], d.subtree_first_moment[i], d.subtree_inertia[i]
        _transform_point(rotation, translation, m.lever[i], point)
        _matmul3(rotation, m.inertia[i], rotated_inertia)
        for r in range(3):
            first_moment[r] = mass * point[r]
            for c in range(3):
                inertia[r, c] = (rotated_inertia[r, 0] * rotation[c, 0]
                                 + rotated_inertia[r, 1] * rotation[c, 1]
                                 + rotated_inertia[r, 2] * rotation[c, 2]
                                 - mass * point[r] * point[c])
            inertia[r, r] += mass * (point[0] ** 2 + point[1] ** 2 + point[2] ** 2)
        # Newton-Euler: gravity enters as an upward acceleration of the whole tree.
        for r in range(3):
            cross[r] = acceleration[r] - m.gravity[r]
            cross[3 + r] = acceleration[3 + r]
        _apply_inertia(mass, first_moment, inertia, cross, d.force[i])
        _apply_inertia(mass, first_moment, inertia, velocity, momentum)
        _add_force_cross(velocity, momentum, d.force[i])


@numba.njit(cache=True)
def _backward_pass(m, d):
    """Subtree wrenches and inertias, leaves to root; joint torques ``nle`` and gravity.

    Index 0 (the universe) ends up holding the whole robot: its first moment and the sum of
    all wrenches, which the centre-of-mass terms read.
    """
    d.force[0, :] = 0.0
    d.subtree_first_moment[0, :] = 0.0
    d.subtree_inertia[0, :, :] = 0.0
    g = m.gravity
    for i in range(m.parent.size - 1, 0, -1):
        p = m.parent[i]
        for r in range(6):
            d.force[p, r] += d.force[i, r]
        for r in range(3):
            d.subtree_first_moment[p, r] += d.subtree_first_moment[i, r]
            for c in range(3):
                d.subtree_inertia[p, r, c] += d.subtree_inertia[i, r, c]
        # tau = S . F over the subtree; holding up its weight alone takes -(M g, H x g).
        h = d.subtree_first_moment[i]
        weight_moment = d.scratch_point
        _cross(h, g, weight_moment)
        mass = m.subtree_mass[i]
        for k in range(m.idx_v[i], m.idx_v[i] + m.nv_joint[i]):
            axis = d.motion_axes[k]
            d.nonlinear_effects[k] = _dot6(axis, d.force[i])
            d.gravity_torques[k] = -(mass * (axis[0] * g[0] + axis[1] * g[1] + axis[2] * g[2])
                                     + axis[3] * weight_moment[0] + axis[4] * weight_moment[1]
                                     + axis[5] * weight_moment[2])


@numba.njit(cache=True)
def _mass_matrix(m, d):
    """Composite-rigid-body algorithm in the world frame, and the CoM Jacobian on the way.

    Column ``k`` of ``M`` pairs the momentum ``F = Ic S_k`` of the subtree moved by dof ``k``
    with the axes of ``k`` and of its ancestors; the linear part of ``F`` over the total mass
    is column ``k`` of the CoM Jacobian. Entries between unrelated dofs stay at zero.
    """
    momentum = d.scratch_motion[0]
    for k in range(m.dof_joint.size):
        i = m.dof_joint[k]
        _apply_inertia(m.subtree_mass[i], d.subtree_first_moment[i], d.subtree_inertia[i],
                       d.motion_axes[k], momentum)
        for r in range(3):
            d.com_jacobian[r, k] = momentum[r] / m.total_mass
        a = k
        while a >= 0:
            value = _dot6(d.motion_axes[a], momentum)
            d.mass_matrix[a, k] = value
            d.mass_matrix[k, a] = value
            a = m.dof_parent[a]


@numba.njit(cache=True)
def _center_of_mass(v, m, d):
    """CoM position, velocity (``Jcom v``) and drift, by Newton: ``sum f = M (a_com - g)``."""
    for r in range(3):
        d.com_position[r] = d.subtree_first_moment[0, r] / m.total_mass
        d.com_drift[r] = d.force[0, r] / m.total_mass + m.gravity[r]
        s = 0.0
        for k in range(v.size):
            s += d.com_jacobian[r, k] * v[k]
        d.com_velocity[r] = s


@numba.njit(cache=True)
def _frames(m, d):
    """Frame placements, and Jacobians, velocities and classical drifts at the frame origins,
    in world-aligned axes (Pinocchio's ``LOCAL_WORLD_ALIGNED``).

    A motion ``(v, w)`` at the origin moves the point ``p`` with ``v + w x p``; the classical
    acceleration adds ``w x (velocity of p)`` to the spatial one.
    """
    cross = d.scratch_point
    for f in range(m.frame_joint.size):
        j = m.frame_joint[f]
        rotation, position = d.frame_rotation[f], d.frame_position[f]
        _matmul3(d.joint_rotation[j], m.frame_placement_rotation[f], rotation)
        _transform_point(d.joint_rotation[j], d.joint_translation[j],
                         m.frame_placement_translation[f], position)
        jacobian = d.frame_jacobian[f]
        k = m.frame_last_dof[f]
        while k >= 0:  # the dofs that move the frame; the other columns stay at zero
            axis = d.motion_axes[k]
            _cross(axis[3:], position, cross)
            for r in range(3):
                jacobian[r, k] = axis[r] + cross[r]
                jacobian[3 + r, k] = axis[3 + r]
            k = m.dof_parent[k]
        velocity, acceleration = d.velocity[j], d.bias_acceleration[j]
        frame_velocity, drift = d.frame_velocity[f], d.frame_drift[f]
        _cross(velocity[3:], position, cross)
        for r in range(3):
            frame_velocity[r] = velocity[r] + cross[r]
            frame_velocity[3 + r] = velocity[3 + r]
        _cross(acceleration[3:], position, cross)
        for r in range(3):
            drift[r] = acceleration[r] + cross[r]
            drift[3 + r] = acceleration[3 + r]
        _cross(velocity[3:], frame_velocity[:3], cross)
        for r in range(3):
            drift[r] += cross[r]


@numba.njit(cache=True)
def _update(q, v, model, data):
    """Every output of RobotKinematics at ``(q, v)``.

    Args:
        q: Configuration; float64 (nq,).
        v: Velocity; float64 (nv,).
        model: The model record array (1,).
        data: The data record array (1,), written in place.

    Returns:
        ``_DONE``, or ``_NOT_FINITE`` / ``_WRONG_SIZE`` having written nothing.
    """
    m, d = model[0], data[0]
    if q.size != d.q.size or v.size != d.v.size:
        return _WRONG_SIZE
    for k in range(q.size):
        if not np.isfinite(q[k]):
            return _NOT_FINITE
    for k in range(v.size):
        if not np.isfinite(v[k]):
            return _NOT_FINITE
    d.q[:] = q
    d.v[:] = v
    _forward_pass(d.q, d.v, m, d)
    _backward_pass(m, d)
    _mass_matrix(m, d)
    _center_of_mass(d.v, m, d)
    _frames(m, d)
    return _DONE
