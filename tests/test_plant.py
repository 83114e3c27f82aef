"""Plant presets and changes reach MuJoCo, and never the controller's model."""

import mujoco
import numpy as np
import pytest

from sim.mujoco_robot import physics_steps_per_period
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS, JointPhysics, Plant
from sim.simulator import Go2Simulator
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.model.description import JOINT_NAMES


def joint_values(sim: Go2Simulator, name: str) -> tuple[float, float, float]:
    dof = sim.model.jnt_dofadr[mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_JOINT, name)]
    return (float(sim.model.dof_damping[dof]), float(sim.model.dof_frictionloss[dof]),
            float(sim.model.dof_armature[dof]))


def test_default_plant_is_menagerie_and_reaches_mujoco():
    sim = Go2Simulator()
    assert DEFAULT_PLANT == "menagerie" and sim.plant == Plant.preset("menagerie")
    for name in JOINT_NAMES:
        assert joint_values(sim, name) == pytest.approx((2.0, 0.2, 0.01))
    foot = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_GEOM, "FR_foot_sphere")
    assert sim.model.geom_condim[foot] == 6
    np.testing.assert_allclose(sim.model.geom_friction[foot], [0.8, 0.02, 0.01])
    assert sim.model.geom_size[foot, 0] == pytest.approx(0.022)
    assert sim.model.opt.impratio == 100.0
    assert sim.model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC


def test_identified_preset_per_joint_type():
    sim = Go2Simulator(plant="identified")
    assert joint_values(sim, "RL_hip_joint") == pytest.approx((0.2, 0.25, 0.02))
    assert joint_values(sim, "FR_thigh_joint") == pytest.approx((0.2, 0.2, 0.02))
    assert joint_values(sim, "FL_calf_joint") == pytest.approx((0.2, 1.0, 0.02))


def test_ideal_preset_has_frictionless_joints():
    sim = Go2Simulator(plant="ideal")
    assert not sim.model.dof_damping.any() and not sim.model.dof_frictionloss.any()
    assert not sim.model.dof_armature.any()


def test_with_params_changes_one_joint_type_or_all():
    plant = Plant.preset("identified").with_params(calf_friction_loss=1.4, joint_damping=0.3)
    assert plant.calf == JointPhysics(0.3, 1.4, 0.02)
    assert plant.hip == JointPhysics(0.3, 0.25, 0.02)
    assert plant.name == "identified + calf_friction_loss=1.4, joint_damping=0.3"
    assert Plant.preset("ideal").with_params() == Plant.preset("ideal")


def test_payload_sits_where_asked():
    sim = Go2Simulator(plant=Plant().with_params(payload_kg=2.0, payload_offset_m=(0.05, 0, 0)))
    body = sim.model.body("payload")
    assert body.mass[0] == pytest.approx(2.0)
    np.testing.assert_allclose(sim.model.body_pos[body.id], [0.05, 0.0, 0.0])
    assert sim.model.body_parentid[body.id] == sim.model.body("base").id


def test_the_controller_model_is_the_urdf_whatever_the_plant(description):
    for name in PLANT_PRESETS:
        sim = Go2Simulator(plant=Plant.preset(name).with_params(payload_kg=1.0))
        assert sim.model.body_mass.sum() == pytest.approx(description.total_mass + 1.0, rel=1e-6)
    model = description.build_model()
    assert model.nv == 18 and sum(i.mass for i in model.inertias) == pytest.approx(
        description.total_mass)
    assert not np.any(model.damping) and not np.any(model.friction)


@pytest.mark.parametrize(("params", "error", "message"), [
    ({"joint_damping": -1.0}, ConfigurationError,
     r"hip_damping: expected a value in \[0, 10\], received -1"),
    ({"calf_friction_loss": 9.0}, ConfigurationError,
     r"calf_friction_loss: expected a value in \[0, 5\], received 9"),
    ({"foot_friction": 0.0}, ConfigurationError,
     r"foot_friction: expected a value in \[0.05, 5\], received 0"),
    ({"payload_offset_m": (1, 2)}, ConfigurationError,
     r"payload_offset_m: expected three numbers \(x, y, z\) \[m\], received \(1, 2\)"),
    ({"condim": 5}, ConfigurationError, r"condim: expected 3, 4 or 6, received 5"),
    ({"knee_damping": 1.0}, UnknownNameError,
     r"unknown plant parameter 'knee_damping'; valid plant parameters: joint_damping, "),
])
def test_bad_plant_parameters_name_the_field(params, error, message):
    with pytest.raises(error, match=message):
        Plant.preset("menagerie").with_params(**params)


def test_unknown_preset_lists_the_presets():
    with pytest.raises(UnknownNameError, match="unknown plant preset 'real'; valid plant presets: "
                                               "menagerie, unitree-mujoco, identified, ideal"):
        Plant.preset("real")


@pytest.mark.parametrize(("period", "timestep", "steps"), [(1e-3, 1e-3, 1), (2e-3, 5e-4, 4),
                                                           (2e-3, 1e-3, 2)])
def test_control_period_in_physics_steps(period, timestep, steps):
    assert physics_steps_per_period(period, timestep) == steps


@pytest.mark.parametrize(("period", "message"), [
    (1.5e-3, (r"control_period_s: expected a whole number of physics steps of 0.001 s "
              r"\(e.g. 0.001, 0.002, 0.004 s\), received 0.0015 s")),
    (0.0, r"control_period_s: expected a value in \(0, 0.1\], received 0"),
    (5e-4, r"control_period_s: expected a whole number of physics steps of 0.001 s"),
])
def test_control_period_that_is_not_whole_physics_steps(period, message):
    with pytest.raises(ConfigurationError, match=message):
        physics_steps_per_period(period, 1e-3)
