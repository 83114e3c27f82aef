"""RobotKinematics against Pinocchio at random states; its derivatives by finite differences."""

from __future__ import annotations

import numba
import numpy as np
import pinocchio as pin
import pytest
from numba.core.runtime import _nrt_python, rtsys

from wbc.core.errors import ConfigurationError, NonFiniteError
from wbc.model import kinematics_kernels as kinematics_module
from wbc.model.kinematics import RobotKinematics

FRAMES = ("FL_foot", "FR_foot", "RL_foot", "RR_foot", "base", "FR_calf", "universe")
OUTPUTS = ("q", "v", "mass_matrix", "nonlinear_effects", "gravity_torques", "com_position",
           "com_velocity", "com_drift", "com_jacobian", "base_rotation", "base_position",
           "frame_rotation", "frame_position", "frame_jacobian", "frame_velocity", "frame_drift")
STEP = 1e-6


def pinocchio_outputs(model: pin.Model, frames, q: np.ndarray, v: np.ndarray) -> dict:
    """The reference: every RobotKinematics output from Pinocchio's own calls."""
    data = model.createData()
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    ids = [model.getFrameId(name) for name in frames]
    world = pin.LOCAL_WORLD_ALIGNED
    com = model.createData()  # CoM terms at zero qdd, as the brief defines the drift
    pin.forwardKinematics(model, com, q, v, np.zeros(model.nv))
    pin.centerOfMass(model, com, pin.KinematicLevel.ACCELERATION, False)
    outputs = {
        "q": q, "v": v,
        "mass_matrix": np.triu(data.M) + np.triu(data.M, 1).T,
        "nonlinear_effects": data.nle,
        "gravity_torques": pin.computeGeneralizedGravity(model, model.createData(), q),
        "com_position": com.com[0], "com_velocity": com.vcom[0], "com_drift": com.acom[0],
        "com_jacobian": pin.jacobianCenterOfMass(model, model.createData(), q),
        "base_rotation": data.oMi[1].rotation, "base_position": data.oMi[1].translation,
        "frame_rotation": np.array([data.oMf[i].rotation for i in ids]),
        "frame_position": np.array([data.oMf[i].translation for i in ids]),
        "frame_jacobian": np.array([pin.getFrameJacobian(model, data, i, world) for i in ids]),
        "frame_velocity": np.array([pin.getFrameVelocity(model, data, i, world).vector
                                    for i in ids]),
        "frame_drift": np.array([pin.getFrameClassicalAcceleration(model, data, i, world).vector
                                 for i in ids]),
    }
    return {name: np.array(value) for name, value in outputs.items()}  # views die with data


def random_state(model: pin.Model, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A configuration on the manifold (neutral pose moved by a random tangent vector), a
    base away from the origin, and a brisk random velocity."""
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-1.5, 1.5, model.nv))
    q[:3] = rng.normal(0.0, 1.0, 3)
    return q, rng.normal(0.0, 2.0, model.nv)


def assert_matches_pinocchio(kinematics: RobotKinematics, model: pin.Model, seed: int) -> None:
    rng = np.random.default_rng(seed)
    for _ in range(20):
        q, v = random_state(model, rng)
        kinematics.compute(q, v)
        for name, expected in pinocchio_outputs(model, kinematics.frames, q, v).items():
            np.testing.assert_allclose(getattr(kinematics, name), expected, rtol=1e-9,
                                       atol=1e-9, err_msg=name)


def any_axis_model(go2: pin.Model) -> pin.Model:
    """A free flyer and four legs of revolute joints about z, x and an unaligned axis, with
    random placements and inertias; sized like the GO2 so it reuses the compiled code."""
    rng = np.random.default_rng(7)
    model = pin.Model()
    model.gravity = go2.gravity
    base = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root_joint")
    model.appendBodyToJoint(base, pin.Inertia.Random(), pin.SE3.Identity())
    axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    for leg in ("FL", "FR", "RL", "RR"):
        parent = base
        for part, joint in (("hip", pin.JointModelRZ()), ("thigh", pin.JointModelRX()),
                            ("calf", pin.JointModelRevoluteUnaligned(axis))):
            placement = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(0.0, 0.2, 3))
            parent = model.addJoint(parent, joint, placement, f"{leg}_{part}_joint")
            model.appendBodyToJoint(parent, pin.Inertia.Random(), pin.SE3.Identity())
        foot = pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.2]))
        model.addFrame(pin.Frame(f"{leg}_foot", parent, 0, foot, pin.FrameType.OP_FRAME))
    model.addFrame(pin.Frame("base", base, 0, pin.SE3.Random(), pin.FrameType.OP_FRAME))
    model.addFrame(pin.Frame("FR_calf", model.getJointId("FR_calf_joint"), 0, pin.SE3.Random(),
                             pin.FrameType.BODY))
    return model


def test_every_output_matches_pinocchio(model):
    kinematics = RobotKinematics(model, FRAMES)
    assert kinematics.total_mass == pytest.approx(pin.computeTotalMass(model), rel=1e-12)
    assert (kinematics.nq, kinematics.nv, kinematics.frames) == (19, 18, FRAMES)
    assert_matches_pinocchio(kinematics, model, seed=0)


def test_revolute_joints_about_any_axis_match_pinocchio(model):
    other = any_axis_model(model)
    assert_matches_pinocchio(RobotKinematics(other, FRAMES), other, seed=1)


def test_jacobians_match_finite_differences_of_placements(model):
    kinematics = RobotKinematics(model, FRAMES)
    rng = np.random.default_rng(2)
    for _ in range(3):
        q, v = random_state(model, rng)
        kinematics.compute(q, v)
        frame_jacobian = kinematics.frame_jacobian.copy()
        com_jacobian = kinematics.com_jacobian.copy()
        for k in range(model.nv):
            placements = []
            for sign in (1.0, -1.0):
                kinematics.compute(pin.integrate(model, q, sign * STEP * np.eye(model.nv)[k]), v)
                placements.append((kinematics.frame_position.copy(),
                                   kinematics.frame_rotation.copy(),
                                   kinematics.com_position.copy()))
            (p_plus, r_plus, c_plus), (p_minus, r_minus, c_minus) = placements
            linear = (p_plus - p_minus) / (2 * STEP)
            angular = np.array([pin.log3(rp @ rm.T) for rp, rm in zip(r_plus, r_minus)])
            np.testing.assert_allclose(frame_jacobian[:, :3, k], linear, atol=1e-5)
            np.testing.assert_allclose(frame_jacobian[:, 3:, k], angular / (2 * STEP), atol=1e-5)
            np.testing.assert_allclose(com_jacobian[:, k], (c_plus - c_minus) / (2 * STEP),
                                       atol=1e-5)


def test_drifts_are_the_time_derivative_of_jacobian_times_v(model):
    kinematics = RobotKinematics(model, FRAMES)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v = random_state(model, rng)
        kinematics.compute(q, v)
        frame_drift, com_drift = kinematics.frame_drift.copy(), kinematics.com_drift.copy()
        rates = []
        for sign in (1.0, -1.0):  # along the motion at constant v: q(t) = q (+) t v
            kinematics.compute(pin.integrate(model, q, sign * STEP * v), v)
            rates.append((kinematics.frame_jacobian @ v, kinematics.com_jacobian @ v))
        (frame_plus, com_plus), (frame_minus, com_minus) = rates
        np.testing.assert_allclose(frame_drift, (frame_plus - frame_minus) / (2 * STEP),
                                   atol=1e-5)
        np.testing.assert_allclose(com_drift, (com_plus - com_minus) / (2 * STEP), atol=1e-5)


@numba.njit
def _ticks(q, v, model, data, count):
    for _ in range(count):
        kinematics_module._update(q, v, model, data)


def test_update_writes_in_place_and_allocates_nothing(model):
    kinematics = RobotKinematics(model, FRAMES)
    arrays = {name: getattr(kinematics, name) for name in OUTPUTS}
    rng = np.random.default_rng(4)
    q, v = random_state(model, rng)
    kinematics.compute(q, v)
    before = {name: array.copy() for name, array in arrays.items()}
    q, v = random_state(model, rng)
    kinematics.compute(q, v)
    for name, array in arrays.items():
        assert getattr(kinematics, name) is array, name
        assert not np.array_equal(array, before[name]), f"{name} was not updated"
    # The compiled tick allocates nothing: 200 ticks cost the same NRT allocations as one
    # (those of passing the arguments in).
    enabled = _nrt_python.memsys_stats_enabled()
    _nrt_python.memsys_enable_stats()
    try:
        counts = []
        for count in (1, 200):
            start = rtsys.get_allocation_stats()
            _ticks(q, v, kinematics._model, kinematics._data, count)
            counts.append(rtsys.get_allocation_stats().alloc - start.alloc)
    finally:
        if not enabled:
            _nrt_python.memsys_disable_stats()
    assert counts[0] == counts[1], counts


def test_frame_and_model_errors_name_the_valid_choices(model):
    with pytest.raises(ConfigurationError) as err:
        RobotKinematics(model, ["FL_foot", "hand"])
    assert str(err.value).startswith("frames: unknown frame 'hand'; valid frames: ['universe', "
                                     "'root_joint', 'base', ")
    assert "'RR_foot'" in str(err.value)
    kinematics = RobotKinematics(model, ["FR_foot", "RL_foot"])
    assert kinematics.frame_index("RL_foot") == 1
    with pytest.raises(ConfigurationError, match=r"^frame: 'base' is not computed; computed "
                                                 r"frames: \['FR_foot', 'RL_foot'\]$"):
        kinematics.frame_index("base")
    ball = pin.Model()
    ball.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(ConfigurationError, match="model: joint 'ball' is a JointModelSpherical; "
                                                 "RobotKinematics supports a JointModelFreeFlyer"):
        RobotKinematics(ball, [])


def test_update_refuses_non_finite_states_and_leaves_the_outputs(model):
    kinematics = RobotKinematics(model, FRAMES)
    q, v = random_state(model, np.random.default_rng(6))
    assert kinematics.compute(q, v) is True
    before = {name: getattr(kinematics, name).copy() for name in OUTPUTS}
    for bad_q, bad_v in ((np.where(np.arange(19) == 5, np.nan, q), v),
                         (q, np.where(np.arange(18) == 17, -np.inf, v))):
        assert kinematics.compute(bad_q, bad_v) is False
        for name, value in before.items():
            np.testing.assert_array_equal(getattr(kinematics, name), value, err_msg=name)


def test_compute_checks_sizes_and_checked_compute_validates(model):
    kinematics = RobotKinematics(model, FRAMES)
    q, v = random_state(model, np.random.default_rng(5))
    with pytest.raises(ConfigurationError, match=r"^RobotKinematics.compute: expected q of shape "
                                                 r"\(19,\) and v of shape \(18,\), received "
                                                 r"\(7,\) and \(18,\)$"):
        kinematics.compute(q[:7], v)
    kinematics.checked_compute(q.tolist(), v.tolist())
    np.testing.assert_array_equal(kinematics.q, q)
    with pytest.raises(ConfigurationError, match=r"^v: expected an array of shape \(18,\), "
                                                 r"received shape \(17,\)$"):
        kinematics.checked_compute(q, v[1:])
    with pytest.raises(NonFiniteError, match=r"^q: non-finite value at index \[3\]"):
        kinematics.checked_compute(np.where(np.arange(19) == 3, np.nan, q), v)
