"""RobotKinematics against Pinocchio at random states, and its Jacobians against finite differences."""

import numpy as np
import pinocchio as pin
import pytest

from tasks import RobotKinematics
from wbc.errors import ConfigurationError

FRAMES = ("FL_foot", "FR_foot", "RL_foot", "RR_foot", "base", "FR_calf", "imu_joint")


def random_state(model, rng):
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-1.0, 1.0, model.nv))
    q[:3] = rng.normal(size=3)
    return q, 2.0 * rng.normal(size=model.nv)


def pinocchio_reference(model, q, v):
    """Every output of RobotKinematics, from Pinocchio's own calls."""
    data = model.createData()
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    pin.centerOfMass(model, data, pin.KinematicLevel.ACCELERATION, False)
    world = pin.LOCAL_WORLD_ALIGNED
    ids = [model.getFrameId(f) for f in FRAMES]
    return {
        "mass_matrix": np.triu(data.M) + np.triu(data.M, 1).T,
        "nonlinear_effects": data.nle,
        "com_position": data.com[0], "com_velocity": data.vcom[0], "com_drift": data.acom[0],
        "com_jacobian": data.Jcom,
        "base_rotation": data.oMi[1].rotation, "base_position": data.oMi[1].translation,
        "frame_rotation": np.array([data.oMf[i].rotation for i in ids]),
        "frame_position": np.array([data.oMf[i].translation for i in ids]),
        "frame_jacobian": np.array([pin.getFrameJacobian(model, data, i, world) for i in ids]),
        "frame_velocity": np.array([pin.getFrameVelocity(model, data, i, world).vector
                                    for i in ids]),
        "frame_drift": np.array([pin.getFrameClassicalAcceleration(model, data, i, world).vector
                                 for i in ids]),
    }


def test_every_output_matches_pinocchio(model):
    kinematics = RobotKinematics(model, FRAMES)
    rng = np.random.default_rng(0)
    assert kinematics.total_mass == pytest.approx(pin.computeTotalMass(model))
    for _ in range(20):
        q, v = random_state(model, rng)
        kinematics.update(q, v)
        for name, expected in pinocchio_reference(model, q, v).items():
            np.testing.assert_allclose(getattr(kinematics, name), expected, atol=1e-10,
                                       rtol=1e-10, err_msg=name)


def test_jacobians_and_drifts_against_finite_differences(model):
    kinematics = RobotKinematics(model, FRAMES)
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(5):
        q, v = random_state(model, rng)
        plus, minus = pin.integrate(model, q, h * v), pin.integrate(model, q, -h * v)

        def at(qq):
            kinematics.update(qq, v)
            return (kinematics.frame_position.copy(), kinematics.com_position.copy(),
                    np.einsum("fij,j->fi", kinematics.frame_jacobian, v),
                    kinematics.com_jacobian @ v)

        fp, cp, fjv, cjv = at(plus)
        fm, cm, fjm, cjm = at(minus)
        f0, c0, fj0, cj0 = at(q)
        frame_drift, com_drift = kinematics.frame_drift.copy(), kinematics.com_drift.copy()
        np.testing.assert_allclose(fj0[:, :3], (fp - fm) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(cj0, (cp - cm) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(frame_drift, (fjv - fjm) / (2 * h), atol=1e-4)
        np.testing.assert_allclose(com_drift, (cjv - cjm) / (2 * h), atol=1e-4)


def test_outputs_are_updated_in_place(model):
    kinematics = RobotKinematics(model, FRAMES)
    arrays = {name: getattr(kinematics, name) for name in
              ("mass_matrix", "nonlinear_effects", "frame_jacobian", "frame_drift", "com_jacobian")}
    q, v = random_state(model, np.random.default_rng(2))
    kinematics.update(q, v)
    for name, array in arrays.items():
        assert getattr(kinematics, name) is array, name
    assert np.abs(kinematics.mass_matrix).sum() > 0


def test_unknown_frame_and_unsupported_joint(model):
    with pytest.raises(ConfigurationError, match="frames: unknown frame 'hand'; valid frames"):
        RobotKinematics(model, ["hand"])
    with pytest.raises(ConfigurationError, match="'base' is not computed; computed frames"):
        RobotKinematics(model, ["FR_foot"]).frame_index("base")
    spherical = pin.Model()
    spherical.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    with pytest.raises(ConfigurationError, match="joint 'ball' is a JointModelSpherical"):
        RobotKinematics(spherical, [])
