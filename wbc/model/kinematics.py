"""Rigid-body kinematics and dynamics of a floating-base robot, compiled into one call per tick."""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
import pinocchio as pin

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector

# Joint kinds in ``model.kind``: index 0 is Pinocchio's universe, which never moves.
_UNIVERSE, _FREE_FLYER, _REVOLUTE = 0, 1, 2
_PRINCIPAL_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}
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
def _quaternion_rotation(x, y, z, w, out):
    """Rotation matrix of the quaternion ``(x, y, z, w)``, unnormalized like Eigen's."""
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
# scratch); see RobotKinematics._build for their fields.


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
            _quaternion_rotation(q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6], rotation_joint)
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


class RobotKinematics:
    """Kinematics and dynamics of a free-flyer robot with revolute joints, in one compiled call.

    Reads the Pinocchio model once (tree, joint placements, inertias including the fixed
    bodies Pinocchio merged, frames, gravity); each :meth:`update` then replaces Pinocchio's
    ``computeAllTerms``, ``updateFramePlacements``, ``centerOfMass`` and the per-frame
    Jacobian, velocity and acceleration calls with one compiled call that allocates nothing.
    Pinocchio's conventions: ``q = [base position (world) [m], base quaternion (x, y, z, w),
    joint angles [rad]]``, ``v = [base linear velocity [m/s], base angular velocity [rad/s]
    (both in the base frame), joint rates [rad/s]]``.

    Every output below is an array allocated once and overwritten in place by :meth:`update`
    (hold a reference, or ``.copy()`` to keep a value); spatial 6-vectors are (linear;
    angular), world-aligned. The compiled code is specialised to the model's sizes and the
    number of frames: the first update for new sizes compiles (~8 s, then cached on disk).

    Attributes:
        nq, nv: Configuration and velocity sizes.
        frames: Names of the computed frames, in the order of the ``frame_*`` arrays.
        total_mass: Mass of the robot [kg].
        q, v: Copies of the last state (nq,), (nv,).
        mass_matrix: Joint-space inertia ``M`` (nv, nv), symmetric [kg, kg m, kg m^2].
        nonlinear_effects: Coriolis, centrifugal and gravity torques ``C v + g`` (nv,)
            [N, N m] (the base entries are the base-frame wrench).
        gravity_torques: The gravity part ``g`` alone (nv,) [N, N m].
        com_position: World centre of mass (3,) [m].
        com_velocity: Its velocity (3,) [m/s].
        com_drift: Its acceleration at zero ``qdd`` (3,) [m/s^2].
        com_jacobian: ``d com / d v`` (3, nv).
        base_position, base_rotation: World placement of the root joint (3,) [m], (3, 3).
        frame_position, frame_rotation: World placements of the frames (nf, 3) [m],
            (nf, 3, 3).
        frame_jacobian: Jacobians at the frame origins (nf, 6, nv), linear rows [m] then
            angular rows.
        frame_velocity: Velocities of the frame origins (nf, 6) [m/s; rad/s].
        frame_drift: Their classical accelerations at zero ``qdd``, ``dJ/dt v`` (nf, 6)
            [m/s^2; rad/s^2].
    """

    def __init__(self, model: pin.Model, frames: Sequence[str]) -> None:
        """Read the model and allocate every output.

        Args:
            model: A Pinocchio model: an optional free flyer attached to the universe, then
                revolute joints (``JointModelRX/RY/RZ`` or ``JointModelRevoluteUnaligned``).
            frames: Names of the model frames to compute.

        Raises:
            ConfigurationError: An unsupported joint (named, with its type), or a frame name
                the model does not have (the message lists the valid ones).
        """
        self.frames: tuple[str, ...] = tuple(frames)
        self.nq: int = model.nq
        self.nv: int = model.nv
        self._model, self._data = self._build(model)
        record = self._data[0]  # a view: its fields are views of the data record
        self.total_mass: float = float(self._model["total_mass"][0])
        self.q: np.ndarray = record["q"]
        self.v: np.ndarray = record["v"]
        self.mass_matrix: np.ndarray = record["mass_matrix"]
        self.nonlinear_effects: np.ndarray = record["nonlinear_effects"]
        self.gravity_torques: np.ndarray = record["gravity_torques"]
        self.com_position: np.ndarray = record["com_position"]
        self.com_velocity: np.ndarray = record["com_velocity"]
        self.com_drift: np.ndarray = record["com_drift"]
        self.com_jacobian: np.ndarray = record["com_jacobian"]
        self.base_rotation: np.ndarray = record["joint_rotation"][1]
        self.base_position: np.ndarray = record["joint_translation"][1]
        self.frame_rotation: np.ndarray = record["frame_rotation"]
        self.frame_position: np.ndarray = record["frame_position"]
        self.frame_jacobian: np.ndarray = record["frame_jacobian"]
        self.frame_velocity: np.ndarray = record["frame_velocity"]
        self.frame_drift: np.ndarray = record["frame_drift"]

    def _build(self, model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
        """The constant model record and the data record (outputs and scratch).

        Two NumPy records, so that the compiled call takes four arguments: unboxing each
        array argument costs ~50 ns, which forty separate arrays would spend on every tick.
        """
        nj, nv, nf = model.njoints, model.nv, len(self.frames)
        if nj < 2:
            raise ConfigurationError("model: expected at least one joint besides the universe, "
                                     "received none")
        kind, axis = np.zeros(nj, np.int64), np.zeros((nj, 3))
        for i in range(1, nj):
            name = model.joints[i].shortname()
            if name == "JointModelFreeFlyer" and model.parents[i] == 0:
                kind[i] = _FREE_FLYER
            elif name in _PRINCIPAL_AXES:
                kind[i], axis[i, _PRINCIPAL_AXES[name]] = _REVOLUTE, 1.0
            elif name == "JointModelRevoluteUnaligned":
                kind[i], axis[i] = _REVOLUTE, model.joints[i].extract().axis
            else:
                where = " away from the root" if name == "JointModelFreeFlyer" else ""
                raise ConfigurationError(
                    f"model: joint {model.names[i]!r} is a {name}{where}; RobotKinematics "
                    "supports a JointModelFreeFlyer attached to the universe and revolute "
                    "joints (JointModelRX, JointModelRY, JointModelRZ, "
                    "JointModelRevoluteUnaligned)")
        if np.any(np.asarray(model.gravity.angular) != 0.0):
            raise ConfigurationError(f"model: expected a gravity without angular part, "
                                     f"received {model.gravity}")
        names = [frame.name for frame in model.frames]
        unknown = [name for name in self.frames if name not in names]
        if unknown:
            raise ConfigurationError(f"frames: unknown frame {unknown[0]!r}; valid frames: "
                                     f"{names}")
        frame_ids = [model.getFrameId(name) for name in self.frames]

        parent = np.array(model.parents, np.int64)
        idx_v = np.array([j.idx_v for j in model.joints], np.int64)
        nv_joint = np.array([0] + [model.joints[i].nv for i in range(1, nj)], np.int64)
        last_dof = np.where(nv_joint > 0, idx_v + nv_joint - 1, -1)
        dof_parent = np.full(nv, -1, np.int64)  # the next dof up the tree (Featherstone's lambda)
        dof_joint = np.zeros(nv, np.int64)
        for i in range(1, nj):
            for k in range(idx_v[i], idx_v[i] + nv_joint[i]):
                dof_joint[k] = i
                dof_parent[k] = k - 1 if k > idx_v[i] else last_dof[parent[i]]
        mass = np.array([inertia.mass for inertia in model.inertias])
        subtree_mass = mass.copy()
        for i in range(nj - 1, 0, -1):
            subtree_mass[parent[i]] += subtree_mass[i]
        # The universe's own inertia (fixed to the world) does not count, as in Pinocchio.
        subtree_mass[0] -= mass[0]

        f8, i8 = np.float64, np.int64
        model_type = np.dtype([
            ("parent", i8, (nj,)), ("kind", i8, (nj,)), ("idx_q", i8, (nj,)),
            ("idx_v", i8, (nj,)), ("nv_joint", i8, (nj,)), ("dof_parent", i8, (nv,)),
            ("dof_joint", i8, (nv,)), ("frame_joint", i8, (nf,)),
            ("frame_last_dof", i8, (nf,)), ("placement_rotation", f8, (nj, 3, 3)),
            ("placement_translation", f8, (nj, 3)), ("axis", f8, (nj, 3)),
            ("mass", f8, (nj,)), ("lever", f8, (nj, 3)), ("inertia", f8, (nj, 3, 3)),
            ("subtree_mass", f8, (nj,)), ("frame_placement_rotation", f8, (nf, 3, 3)),
            ("frame_placement_translation", f8, (nf, 3)), ("gravity", f8, (3,)),
            ("total_mass", f8),
        ], align=True)
        frame_joint = np.array([model.frames[i].parentJoint for i in frame_ids], np.int64)
        constants = np.zeros(1, model_type)
        for name, value in {
            "parent": parent, "kind": kind, "idx_q": [j.idx_q for j in model.joints],
            "idx_v": idx_v, "nv_joint": nv_joint, "dof_parent": dof_parent,
            "dof_joint": dof_joint, "frame_joint": frame_joint,
            "frame_last_dof": last_dof[frame_joint],
            "placement_rotation": [placement.rotation for placement in model.jointPlacements],
            "placement_translation": [placement.translation
                                      for placement in model.jointPlacements],
            "axis": axis, "mass": mass, "lever": [inertia.lever for inertia in model.inertias],
            "inertia": [inertia.inertia for inertia in model.inertias],
            "subtree_mass": subtree_mass,
            "frame_placement_rotation": np.reshape(
                [model.frames[i].placement.rotation for i in frame_ids], (nf, 3, 3)),
            "frame_placement_translation": np.reshape(
                [model.frames[i].placement.translation for i in frame_ids], (nf, 3)),
            "gravity": model.gravity.linear, "total_mass": subtree_mass[0],
        }.items():
            constants[name][0] = value

        data_type = np.dtype([
            ("q", f8, (self.nq,)), ("v", f8, (nv,)), ("mass_matrix", f8, (nv, nv)),
            ("nonlinear_effects", f8, (nv,)), ("gravity_torques", f8, (nv,)),
            ("com_position", f8, (3,)), ("com_velocity", f8, (3,)), ("com_drift", f8, (3,)),
            ("com_jacobian", f8, (3, nv)), ("joint_rotation", f8, (nj, 3, 3)),
            ("joint_translation", f8, (nj, 3)), ("frame_rotation", f8, (nf, 3, 3)),
            ("frame_position", f8, (nf, 3)), ("frame_jacobian", f8, (nf, 6, nv)),
            ("frame_velocity", f8, (nf, 6)), ("frame_drift", f8, (nf, 6)),
            ("motion_axes", f8, (nv, 6)), ("velocity", f8, (nj, 6)),
            ("bias_acceleration", f8, (nj, 6)), ("force", f8, (nj, 6)),
            ("subtree_first_moment", f8, (nj, 3)), ("subtree_inertia", f8, (nj, 3, 3)),
            ("scratch_rotation", f8, (2, 3, 3)), ("scratch_motion", f8, (2, 6)),
            ("scratch_point", f8, (3,)),
        ], align=True)
        data = np.zeros(1, data_type)
        data["joint_rotation"][0, 0] = np.eye(3)  # the universe: never written again
        return constants, data

    def frame_index(self, name: str) -> int:
        """Index of frame ``name`` in the ``frame_*`` arrays.

        Raises:
            ConfigurationError: ``name`` is not one of :attr:`frames` (they are listed).
        """
        if name not in self.frames:
            raise ConfigurationError(f"frame: {name!r} is not computed; computed frames: "
                                     f"{list(self.frames)}")
        return self.frames.index(name)

    def update(self, q: np.ndarray, v: np.ndarray) -> bool:
        """Recompute every output at the state ``(q, v)``: one compiled call, no allocation.

        The hot-path entry: ``q`` and ``v`` must be float64 NumPy arrays; their sizes and
        finiteness are checked in the compiled call. Use :meth:`checked_update` for other
        inputs (lists, other dtypes) or to have a non-finite value raise.

        Args:
            q: Configuration (nq,): base position [m], quaternion (x, y, z, w), joints [rad].
            v: Velocity (nv,): base linear [m/s] and angular [rad/s] in the base frame,
                joint rates [rad/s].

        Returns:
            True; False, leaving every output (``q`` and ``v`` included) as it was, when
            ``q`` or ``v`` holds a NaN or an infinite value.

        Raises:
            ConfigurationError: ``q`` or ``v`` has the wrong size.
        """
        status = _update(q, v, self._model, self._data)
        if status == _DONE:
            return True
        if status == _NOT_FINITE:
            return False
        raise ConfigurationError(
            f"RobotKinematics.update: expected q of shape ({self.nq},) and v of shape "
            f"({self.nv},), received {np.shape(q)} and {np.shape(v)}")

    def checked_update(self, q: np.ndarray, v: np.ndarray) -> None:
        """:meth:`update` after converting and validating the inputs (off the hot path).

        Raises:
            ConfigurationError: Not numeric, or the wrong shape.
            NonFiniteError: A NaN or infinite entry.
        """
        self.update(as_vector("q", q, self.nq), as_vector("v", v, self.nv))
