"""RobotKinematics' records, read from a Pinocchio model once: the tree, the joints' placements
and axes, the inertias, the frames and gravity (constant), and the outputs and scratch.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from wbc.core.errors import ConfigurationError
from wbc.model.kinematics_kernels import _FREE_FLYER, _REVOLUTE

_PRINCIPAL_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}


def kinematics_records(model: pin.Model, frames: tuple[str, ...]
                       ) -> tuple[np.ndarray, np.ndarray]:
    """The constant model record and the data record (outputs and scratch).

    Two NumPy records, so that the compiled call takes four arguments: unboxing each
    array argument costs ~50 ns, which forty separate arrays would spend on every tick.

    Args:
        model: See :class:`wbc.model.kinematics.RobotKinematics`.
        frames: The names of the frames to compute, in their order.

    Raises:
        ConfigurationError: An unsupported joint (named, with its type), or a frame name
            the model does not have (the message lists the valid ones).
    """
    nj, nv, nf = model.njoints, model.nv, len(frames)
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
    unknown = [name for name in frames if name not in names]
    if unknown:
        raise ConfigurationError(f"frames: unknown frame {unknown[0]!r}; valid frames: "
                                 f"{names}")
    frame_ids = [model.getFrameId(name) for name in frames]

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
        ("q", f8, (model.nq,)), ("v", f8, (nv,)), ("mass_matrix", f8, (nv, nv)),
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
