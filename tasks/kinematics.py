"""Compiled kinematics and dynamics of a floating-base tree of revolute joints, in one call."""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
import pinocchio as pin

from wbc.errors import ConfigurationError

_UNIVERSE, _FREE_FLYER, _REVOLUTE = 0, 1, 2
_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}


@numba.njit(cache=True)
def _cross(a, b, out):
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@numba.njit(cache=True)
def _motion_cross(v, m, out):
    """``v x m`` for spatial motions stored (linear, angular)."""
    out[0] = v[4] * m[2] - v[5] * m[1] + v[1] * m[5] - v[2] * m[4]
    out[1] = v[5] * m[0] - v[3] * m[2] + v[2] * m[3] - v[0] * m[5]
    out[2] = v[3] * m[1] - v[4] * m[0] + v[0] * m[4] - v[1] * m[3]
    out[3] = v[4] * m[5] - v[5] * m[4]
    out[4] = v[5] * m[3] - v[3] * m[5]
    out[5] = v[3] * m[4] - v[4] * m[3]


@numba.njit(cache=True)
def _inertia_times(m, mc, I, motion, out):
    """World spatial inertia (mass, first moment, rotational inertia about the origin) times
    a spatial motion at the origin: the momentum (linear; angular about the origin)."""
    v0, v1, v2, w0, w1, w2 = motion[0], motion[1], motion[2], motion[3], motion[4], motion[5]
    out[0] = m * v0 - (mc[1] * w2 - mc[2] * w1)
    out[1] = m * v1 - (mc[2] * w0 - mc[0] * w2)
    out[2] = m * v2 - (mc[0] * w1 - mc[1] * w0)
    out[3] = mc[1] * v2 - mc[2] * v1 + I[0, 0] * w0 + I[0, 1] * w1 + I[0, 2] * w2
    out[4] = mc[2] * v0 - mc[0] * v2 + I[1, 0] * w0 + I[1, 1] * w1 + I[1, 2] * w2
    out[5] = mc[0] * v1 - mc[1] * v0 + I[2, 0] * w0 + I[2, 1] * w1 + I[2, 2] * w2


@numba.njit(cache=True)
def _update(q, v, joints, place_R, place_p, mass, lever, inertia, support, gravity,
            frame_joint, frame_R, frame_p, rotations, vectors3, vectors6, scalars, small, J,
            M, nle, com3, Jcom, f_R, f_p, f_J, f_v, f_a):
    """Every output of :class:`RobotKinematics`, world frame, spatial vectors at the origin.

    Arrays are packed by shape to keep the call's argument count (and its cost) low:
    ``joints`` (nj, 5) holds parents, types, axes, idx_q, idx_v; the scratch stacks hold
    rotations (oR, bI, cI), 3-vectors (op, bmc, cmc), 6-vectors (vel, acc, force),
    scalars (bm, cm) and small temporaries.
    """
    parents, types, axes, idx_q, idx_v = (joints[:, 0], joints[:, 1], joints[:, 2],
                                          joints[:, 3], joints[:, 4])
    oR, bI, cI = rotations[0], rotations[1], rotations[2]
    op, bmc, cmc = vectors3[0], vectors3[1], vectors3[2]
    vel, acc, force = vectors6[0], vectors6[1], vectors6[2]
    bm, cm = scalars[0], scalars[1]
    tmp6, h = small[0], small[1]
    tmp3, cw, c, pv, pa = small[2, :3], small[3, :3], small[4, :3], small[5, :3], small[6, :3]
    Rpp, Rj = small[7:10, :3], small[10:13, :3]
    com, vcom, acom = com3[0], com3[1], com3[2]
    total = 0.0
    for k in range(q.size):
        total += q[k]
    for k in range(v.size):
        total += v[k]
    if not np.isfinite(total):  # a NaN or infinite input: leave every output as it was
        return False
    nj = parents.size
    nv = v.size
    J[:, :] = 0.0
    for i in range(1, nj):
        p = parents[i]
        # Joint placement in the world: oMi = oMp * placement * joint(q).
        for a in range(3):
            for b in range(3):
                s = 0.0
                for k in range(3):
                    s += oR[p, a, k] * place_R[i, k, b]
                Rpp[a, b] = s
            op[i, a] = op[p, a] + oR[p, a, 0] * place_p[i, 0] + oR[p, a, 1] * place_p[i, 1] \
                + oR[p, a, 2] * place_p[i, 2]
        if types[i] == _FREE_FLYER:
            x, y, z, w = q[idx_q[i] + 3], q[idx_q[i] + 4], q[idx_q[i] + 5], q[idx_q[i] + 6]
            Rj[0, 0], Rj[0, 1], Rj[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), \
                2 * (x * z + y * w)
            Rj[1, 0], Rj[1, 1], Rj[1, 2] = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), \
                2 * (y * z - x * w)
            Rj[2, 0], Rj[2, 1], Rj[2, 2] = 2 * (x * z - y * w), 2 * (y * z + x * w), \
                1 - 2 * (x * x + y * y)
            for a in range(3):
                op[i, a] += (Rpp[a, 0] * q[idx_q[i]] + Rpp[a, 1] * q[idx_q[i] + 1]
                             + Rpp[a, 2] * q[idx_q[i] + 2])
        else:
            cos, sin = np.cos(q[idx_q[i]]), np.sin(q[idx_q[i]])
            Rj[:, :] = 0.0
            a0 = axes[i]
            a1, a2 = (a0 + 1) % 3, (a0 + 2) % 3
            Rj[a0, a0] = 1.0
            Rj[a1, a1], Rj[a1, a2], Rj[a2, a1], Rj[a2, a2] = cos, -sin, sin, cos
        for a in range(3):
            for b in range(3):
                oR[i, a, b] = Rpp[a, 0] * Rj[0, b] + Rpp[a, 1] * Rj[1, b] + Rpp[a, 2] * Rj[2, b]
        # Jacobian columns at the world origin: a unit motion of the joint, in the world.
        col = idx_v[i]
        if types[i] == _FREE_FLYER:
            for k in range(3):
                for a in range(3):
                    J[a, col + k] = oR[i, a, k]                   # linear unit motions
                    J[3 + a, col + 3 + k] = oR[i, a, k]           # angular unit motions
                _cross(op[i], oR[i, :, k], tmp3)                  # p x w
                for a in range(3):
                    J[a, col + 3 + k] = tmp3[a]
        else:
            for a in range(3):
                J[3 + a, col] = oR[i, a, axes[i]]
            _cross(op[i], oR[i, :, axes[i]], tmp3)
            for a in range(3):
                J[a, col] = tmp3[a]
        # Velocity and bias acceleration (qdd = 0): a_i = a_p + (v_p x J_i) qd_i.
        ndof = 6 if types[i] == _FREE_FLYER else 1
        for a in range(6):
            vel[i, a] = vel[p, a]
            acc[i, a] = acc[p, a]
        for k in range(ndof):
            qd = v[col + k]
            _motion_cross(vel[p], J[:, col + k], tmp6)
            for a in range(6):
                vel[i, a] += J[a, col + k] * qd
                acc[i, a] += tmp6[a] * qd
        # Body inertia in the world, about the origin: mass, first moment, rotation part.
        m = mass[i]
        for a in range(3):
            cw[a] = op[i, a] + oR[i, a, 0] * lever[i, 0] + oR[i, a, 1] * lever[i, 1] \
                + oR[i, a, 2] * lever[i, 2]
        bm[i] = m
        for a in range(3):
            bmc[i, a] = m * cw[a]
        for a in range(3):
            for b in range(3):
                s = 0.0
                for k in range(3):
                    for l in range(3):
                        s += oR[i, a, k] * inertia[i, k, l] * oR[i, b, l]
                bI[i, a, b] = s - m * cw[a] * cw[b]
            bI[i, a, a] += m * (cw[0] * cw[0] + cw[1] * cw[1] + cw[2] * cw[2])
    # Body wrenches f_i = I_i (a_i - g) + v_i x* (I_i v_i), composite inertias and forces.
    for i in range(nj - 1, 0, -1):
        for a in range(6):
            tmp6[a] = acc[i, a] - (gravity[a] if a < 3 else 0.0)
        _inertia_times(bm[i], bmc[i], bI[i], tmp6, force[i])
        _inertia_times(bm[i], bmc[i], bI[i], vel[i], h)
        w = vel[i]
        # v x* h = (w x h_lin, w x h_ang + v_lin x h_lin)
        force[i, 0] += w[4] * h[2] - w[5] * h[1]
        force[i, 1] += w[5] * h[0] - w[3] * h[2]
        force[i, 2] += w[3] * h[1] - w[4] * h[0]
        force[i, 3] += w[4] * h[5] - w[5] * h[4] + w[1] * h[2] - w[2] * h[1]
        force[i, 4] += w[5] * h[3] - w[3] * h[5] + w[2] * h[0] - w[0] * h[2]
        force[i, 5] += w[3] * h[4] - w[4] * h[3] + w[0] * h[1] - w[1] * h[0]
        cm[i] = bm[i]
        cmc[i] = bmc[i]
        cI[i] = bI[i]
    for i in range(nj - 1, 1, -1):  # accumulate subtrees into their parents (world: no transform)
        p = parents[i]
        if p > 0:
            cm[p] += cm[i]
            for a in range(3):
                cmc[p, a] += cmc[i, a]
                for b in range(3):
                    cI[p, a, b] += cI[i, a, b]
            for a in range(6):
                force[p, a] += force[i, a]
    # nle_k = J_k . F_subtree(k); M[k, j] = J_k . (Ic_j J_j), k an ancestor of j (or j).
    for i in range(1, nj):
        ndof = 6 if types[i] == _FREE_FLYER else 1
        for k in range(ndof):
            col = idx_v[i] + k
            s = 0.0
            for a in range(6):
                s += J[a, col] * force[i, a]
            nle[col] = s
            _inertia_times(cm[i], cmc[i], cI[i], J[:, col], tmp6)
            for r in range(nv):
                if support[i, r] and r <= col:
                    s = 0.0
                    for a in range(6):
                        s += J[a, r] * tmp6[a]
                    M[r, col] = s
                    M[col, r] = s
    # Centre of mass: position, velocity, Jacobian, drift.
    total = 0.0
    com[:] = 0.0
    vcom[:] = 0.0
    acom[:] = 0.0
    Jcom[:, :] = 0.0
    for i in range(1, nj):
        m = bm[i]
        total += m
        for a in range(3):
            c[a] = bmc[i, a] / m
            com[a] += bmc[i, a]
        w = vel[i, 3:]
        _cross(w, c, tmp3)
        for a in range(3):
            pv[a] = vel[i, a] + tmp3[a]                # velocity of the body's CoM
        _cross(acc[i, 3:], c, tmp3)
        for a in range(3):
            pa[a] = acc[i, a] + tmp3[a]
        _cross(w, pv, tmp3)
        for a in range(3):
            vcom[a] += m * pv[a]
            acom[a] += m * (pa[a] + tmp3[a])
        for r in range(nv):
            if support[i, r]:
                Jcom[0, r] += m * (J[0, r] + J[4, r] * c[2] - J[5, r] * c[1])
                Jcom[1, r] += m * (J[1, r] + J[5, r] * c[0] - J[3, r] * c[2])
                Jcom[2, r] += m * (J[2, r] + J[3, r] * c[1] - J[4, r] * c[0])
    com /= total
    vcom /= total
    acom /= total
    Jcom /= total
    # Frames: placement, LOCAL_WORLD_ALIGNED Jacobian, velocity and classical drift.
    for f in range(frame_joint.size):
        j = frame_joint[f]
        for a in range(3):
            for b in range(3):
                f_R[f, a, b] = (oR[j, a, 0] * frame_R[f, 0, b] + oR[j, a, 1] * frame_R[f, 1, b]
                                + oR[j, a, 2] * frame_R[f, 2, b])
            f_p[f, a] = op[j, a] + oR[j, a, 0] * frame_p[f, 0] + oR[j, a, 1] * frame_p[f, 1] \
                + oR[j, a, 2] * frame_p[f, 2]
        pt = f_p[f]
        f_J[f, :, :] = 0.0
        for r in range(nv):
            if support[j, r]:
                f_J[f, 0, r] = J[0, r] + J[4, r] * pt[2] - J[5, r] * pt[1]
                f_J[f, 1, r] = J[1, r] + J[5, r] * pt[0] - J[3, r] * pt[2]
                f_J[f, 2, r] = J[2, r] + J[3, r] * pt[1] - J[4, r] * pt[0]
                f_J[f, 3, r] = J[3, r]
                f_J[f, 4, r] = J[4, r]
                f_J[f, 5, r] = J[5, r]
        w = vel[j, 3:]
        _cross(w, pt, tmp3)
        for a in range(3):
            f_v[f, a] = vel[j, a] + tmp3[a]
            f_v[f, 3 + a] = w[a]
        _cross(acc[j, 3:], pt, tmp3)
        for a in range(3):
            f_a[f, a] = acc[j, a] + tmp3[a]
            f_a[f, 3 + a] = acc[j, 3 + a]
        _cross(w, f_v[f, :3], tmp3)
        for a in range(3):
            f_a[f, a] += tmp3[a]
    return True


class RobotKinematics:
    """Kinematics and dynamics of a free-flyer robot with revolute joints (the GO2), at a
    state, in one compiled call without allocation of outputs.

    Read from the Pinocchio model once (parents, placements, inertias with the fixed
    bodies Pinocchio merged, frames); per tick it replaces ``computeAllTerms``,
    ``updateFramePlacements``, ``centerOfMass`` and the frame Jacobian and acceleration
    calls, with Pinocchio's conventions: ``q = [position, quaternion (x, y, z, w), joints]``,
    ``v = [base linear, base angular (base frame), joint rates]``. Every output is an array
    allocated once and updated in place by :meth:`update`; ``tests/test_kinematics.py``
    checks each against Pinocchio.

    Attributes:
        q, v: The last state.
        mass_matrix (nv, nv), nonlinear_effects (nv,): ``M`` and ``C v + g``.
        com_position, com_velocity [m, m/s], com_drift [m/s^2] (CoM acceleration at zero
            ``qdd``), com_jacobian (3, nv); total_mass [kg].
        base_rotation (3, 3), base_position (3,): the root joint's world placement.
        frame_rotation (nf, 3, 3), frame_position (nf, 3): the frames' world placements.
        frame_jacobian (nf, 6, nv), frame_velocity (nf, 6), frame_drift (nf, 6): linear then
            angular, ``LOCAL_WORLD_ALIGNED`` at each frame's origin; the drift is the
            classical acceleration at zero ``qdd``.
    """

    def __init__(self, model: pin.Model, frames: Sequence[str]):
        """Args:
            model: The Pinocchio model (a free flyer, then revolute joints about x, y or z).
            frames: Names of the frames to compute.
        """
        nj = model.njoints
        self.nq, self.nv = model.nq, model.nv
        self._parents = np.array(model.parents, dtype=np.int64)
        self._types = np.zeros(nj, dtype=np.int64)
        self._axes = np.zeros(nj, dtype=np.int64)
        for i in range(1, nj):
            name = model.joints[i].shortname()
            if name == "JointModelFreeFlyer" and i == 1:
                self._types[i] = _FREE_FLYER
            elif name in _AXES:
                self._types[i], self._axes[i] = _REVOLUTE, _AXES[name]
            else:
                raise ConfigurationError(
                    f"model: joint {model.names[i]!r} is a {name}; RobotKinematics supports a "
                    f"free flyer at the root and revolute joints about x, y or z")
        self._idx_q = np.array([j.idx_q for j in model.joints], dtype=np.int64)
        self._idx_v = np.array([j.idx_v for j in model.joints], dtype=np.int64)
        self._place_R = np.array([p.rotation for p in model.jointPlacements])
        self._place_p = np.array([p.translation for p in model.jointPlacements])
        self._mass = np.array([i.mass for i in model.inertias])
        self._lever = np.array([i.lever for i in model.inertias])
        self._inertia = np.array([i.inertia for i in model.inertias])
        self._gravity = np.asarray(model.gravity.linear, dtype=float).copy()
        self._support = np.zeros((nj, self.nv), dtype=np.bool_)
        for i in range(1, nj):
            j = i
            while j > 0:
                ndof = 6 if self._types[j] == _FREE_FLYER else 1
                self._support[i, self._idx_v[j]:self._idx_v[j] + ndof] = True
                j = self._parents[j]
        self.frames = tuple(frames)
        ids = []
        for frame in self.frames:
            if not model.existFrame(frame):
                names = [f.name for f in model.frames]
                raise ConfigurationError(f"frames: unknown frame {frame!r}; valid frames: {names}")
            ids.append(model.getFrameId(frame))
        self._frame_joint = np.array([model.frames[i].parentJoint for i in ids], dtype=np.int64)
        self._frame_R = np.array([model.frames[i].placement.rotation for i in ids]).reshape(-1, 3, 3)
        self._frame_p = np.array([model.frames[i].placement.translation for i in ids]).reshape(-1, 3)
        nf, nv = len(self.frames), self.nv
        self.total_mass = float(self._mass[1:].sum())
        self.q = np.zeros(self.nq)
        self.v = np.zeros(nv)
        self.mass_matrix = np.zeros((nv, nv))
        self.nonlinear_effects = np.zeros(nv)
        self.com_jacobian = np.zeros((3, nv))
        self.frame_rotation = np.zeros((nf, 3, 3))
        self.frame_position = np.zeros((nf, 3))
        self.frame_jacobian = np.zeros((nf, 6, nv))
        self.frame_velocity = np.zeros((nf, 6))
        self.frame_drift = np.zeros((nf, 6))
        self._joints = np.column_stack([self._parents, self._types, self._axes, self._idx_q,
                                        self._idx_v]).astype(np.int64)
        self._rotations = np.zeros((3, nj, 3, 3))
        self._rotations[0, 0] = np.eye(3)
        self._vectors3 = np.zeros((3, nj, 3))
        self._vectors6 = np.zeros((3, nj, 6))
        self._scalars = np.zeros((2, nj))
        self._small = np.zeros((13, 6))
        self._jacobian = np.zeros((6, nv))
        self._com3 = np.zeros((3, 3))
        self.com_position, self.com_velocity, self.com_drift = self._com3
        self.base_rotation = self._rotations[0, 1]
        self.base_position = self._vectors3[0, 1]

    def frame_index(self, name: str) -> int:
        """Index of a frame in the ``frame_*`` arrays."""
        if name not in self.frames:
            raise ConfigurationError(f"frame: {name!r} is not computed; computed frames: "
                                     f"{list(self.frames)}")
        return self.frames.index(name)

    def update(self, q: np.ndarray, v: np.ndarray) -> bool:
        """Recompute every output at the state ``(q, v)`` (float64 arrays (nq,), (nv,)).

        Returns False, leaving the outputs as they were, when ``q`` or ``v`` holds a NaN or
        an infinite value.
        """
        self.q[:] = q
        self.v[:] = v
        return _update(self.q, self.v, self._joints, self._place_R, self._place_p, self._mass,
                self._lever, self._inertia, self._support, self._gravity, self._frame_joint,
                self._frame_R, self._frame_p, self._rotations, self._vectors3, self._vectors6,
                self._scalars, self._small, self._jacobian, self.mass_matrix,
                self.nonlinear_effects, self._com3, self.com_jacobian, self.frame_rotation,
                self.frame_position, self.frame_jacobian, self.frame_velocity, self.frame_drift)
