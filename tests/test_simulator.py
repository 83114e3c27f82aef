"""The MuJoCo plant agrees with the Pinocchio model, stands under a joint PD, and takes pushes."""

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from sim.simulator import Go2Simulator
from tests.conftest import random_configuration
from wbc.controller.joint_pd_controller import JointPdController
from wbc.core.conventions import mujoco_to_pin
from wbc.core.errors import (
    ConfigurationError,
    NonFiniteError,
    OrderMismatchError,
    UnknownNameError,
)
from wbc.model.description import FOOT_FRAMES, JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES
from wbc.model.joint_map import JointMap
from wbc.robot_io.motor_command import MotorCommand


@pytest.fixture(scope="module")
def sim():
    return Go2Simulator()


def test_mass_and_limits_agree(sim, description):
    assert sim.model.body_mass.sum() == pytest.approx(description.total_mass, rel=0.01)
    np.testing.assert_allclose(sim.model.actuator_forcerange[:, 1], description.effort_limit)
    np.testing.assert_allclose(sim.model.jnt_range[1:, 0], description.position_lower)
    assert sim.timestep_s == 1e-3


def test_foot_positions_agree_at_random_configurations(sim, model):
    data = model.createData()
    rng = np.random.default_rng(7)
    worst = 0.0
    for _ in range(20):
        q = random_configuration(model, rng, scale=1.0)
        sim.reset(q)
        pin.framesForwardKinematics(model, data, q)
        for leg, p_mj in sim.foot_positions().items():
            p_pin = data.oMf[model.getFrameId(FOOT_FRAMES[leg])].translation
            worst = max(worst, np.linalg.norm(p_pin - p_mj))
    assert worst < 1e-3


def test_state_round_trip_preserves_pose_and_joint_order(sim, model):
    rng = np.random.default_rng(11)
    q = random_configuration(model, rng, scale=0.5)
    v = rng.normal(size=18)
    sim.reset(q, v)
    q2, v2 = sim.state()
    np.testing.assert_allclose(q2, q, atol=1e-12)
    np.testing.assert_allclose(v2, v, atol=1e-12)
    for i, name in enumerate(JOINT_NAMES):
        assert sim.data.qpos[7 + i] == pytest.approx(q[7 + i])
        assert sim.model.joint(1 + i).name == name


def test_actuators_in_sdk_order_are_wired_by_name():
    sim = Go2Simulator(actuator_order=UNITREE_SDK_JOINT_NAMES)
    assert sim.model.actuator(0).name == "FR_hip"
    tau = np.zeros(12)
    tau[JOINT_NAMES.index("FR_calf_joint")] = 5.0
    sim.step(tau)
    assert sim.data.ctrl[2] == 5.0  # SDK index 2 is FR_calf
    assert np.count_nonzero(sim.data.ctrl) == 1


def test_stands_five_seconds_under_joint_pd(description):
    sim = Go2Simulator()
    controller = JointPdController(description.pose("standing"))
    z0 = sim.state()[0][2]
    heights = []
    for _ in range(5000):
        q, v = sim.state()
        sim.step(controller.compute(q, v))
        heights.append(sim.state()[0][2])
    assert max(abs(np.array(heights[500:]) - z0)) < 0.01
    forces = sim.foot_contact_forces()
    total = sum(f[2] for f in forces.values())
    assert total == pytest.approx(description.total_mass * 9.81, rel=0.02)
    assert min(f[2] for f in forces.values()) > 20.0


def test_push_moves_the_base_only_while_applied(description):
    sim = Go2Simulator()
    controller = JointPdController(description.pose("standing"))
    for _ in range(200):
        sim.step(controller.compute(*sim.state()))
    y0 = sim.state()[0][1]
    sim.apply_force([0.0, 40.0, 0.0], 0.1)
    base = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, "base")
    applied = []
    for _ in range(150):
        sim.step(controller.compute(*sim.state()))
        applied.append(sim.data.xfrc_applied[base, 1])
    assert applied[:100] == [40.0] * 100
    assert applied[100:] == [0.0] * 50
    assert sim.state()[0][1] - y0 > 1e-3


def test_bad_input(sim):
    with pytest.raises(ConfigurationError,
                       match=r"tau: expected an array of shape \(12,\), received shape \(3,\)"):
        sim.step(np.zeros(3))
    with pytest.raises(UnknownNameError, match="unknown body 'torso'; valid bodys: base"):
        sim.apply_force([1, 0, 0], 0.1, body="torso")
    with pytest.raises(UnknownNameError, match="unknown pose 'crouch'"):
        sim.reset("crouch")
    with pytest.raises(ConfigurationError, match="actuator_order: expected each of the 12"):
        Go2Simulator(actuator_order=JOINT_NAMES[:11] + ("FL_hip_joint",))


def test_drivers_apply_the_pd_law_at_every_physics_step(description):
    """0.5 ms physics under a 2 ms command: the torque follows the state within the period."""
    sim = Go2Simulator(timestep_s=5e-4, actuator_order=UNITREE_SDK_JOINT_NAMES)
    rng = np.random.default_rng(8)
    q0 = sim.state()[0][7:]
    command = MotorCommand(q_des=q0 + rng.uniform(-0.05, 0.05, 12), dq_des=rng.normal(size=12),
                           kp=rng.uniform(20, 60, 12), kd=rng.uniform(1, 3, 12),
                           tau_ff=rng.uniform(-3, 3, 12))
    torques = []
    for _ in range(4):  # one 2 ms command, checked at each of its four physics steps
        q, v = sim.state()
        expected = command.clipped_torque_at(q[7:], v[6:], description.effort_limit)
        sim.step_command(command)
        applied = JointMap(UNITREE_SDK_JOINT_NAMES).from_other(sim.data.actuator_force)
        np.testing.assert_allclose(applied, expected, rtol=1e-9, atol=1e-9)
        torques.append(applied)
    assert np.abs(torques[3] - torques[0]).max() > 1e-3  # the PD acted within the period


def test_drivers_clip_at_the_effort_limits(description):
    sim = Go2Simulator()
    q = sim.state()[0][7:]
    command = MotorCommand(q_des=q + 1.0, dq_des=np.zeros(12), kp=np.full(12, 500.0),
                           kd=np.zeros(12), tau_ff=np.zeros(12))
    sim.step_command(command)
    np.testing.assert_allclose(sim.data.actuator_force, description.effort_limit)


def test_a_bad_motor_command_is_refused_whole(sim):
    before = sim.time_s
    command = MotorCommand.pure_torque(np.zeros(12))
    command.kp[2] = -5.0
    with pytest.raises(ConfigurationError,
                       match=r"motor command: kp: negative gain at joints \[2\]"):
        sim.step_command(command)
    assert sim.time_s == before


def test_a_refused_command_leaves_the_drivers_as_the_last_good_one_set_them(sim):
    # The check and the drivers' write are one compiled call: a command refused at its last
    # joint must not have written the joints before it.
    sim.reset("standing")
    rng = np.random.default_rng(21)
    good = MotorCommand(q_des=rng.normal(size=12), dq_des=rng.normal(size=12),
                        kp=rng.uniform(10, 50, 12), kd=rng.uniform(1, 3, 12),
                        tau_ff=rng.uniform(-3, 3, 12))
    sim.step_command(good)
    drivers = (sim.data.ctrl.copy(), sim.model.actuator_biasprm[:, 1:3].copy())
    for field, value, message in (("q_des", np.nan, r"q_des: non-finite at joints \[11\]"),
                                  ("kd", -1.0, r"kd: negative gain at joints \[11\]"),
                                  ("tau_ff", 1e3, r"tau_ff: beyond the effort .* \[11\]")):
        bad = good.copy()
        bad.q_des[:], bad.kp[:] = 0.1, 99.0  # differs from the good one at every joint
        getattr(bad, field)[11] = value
        with pytest.raises(ConfigurationError, match=f"motor command: {message}"):
            sim.step_command(bad)
        np.testing.assert_array_equal(sim.data.ctrl, drivers[0])
        np.testing.assert_array_equal(sim.model.actuator_biasprm[:, 1:3], drivers[1])
    # Arrays of another type than float64 take NumPy's path to the same drivers' values.
    as_float32 = MotorCommand(**{f: getattr(good, f).astype(np.float32) for f in
                                 ("q_des", "dq_des", "kp", "kd", "tau_ff")})
    expected = (as_float32.tau_ff + as_float32.kp * as_float32.q_des
                + as_float32.kd * as_float32.dq_des)
    sim.step_command(as_float32)
    np.testing.assert_array_equal(sim.data.ctrl, expected)


def test_state_is_the_conventions_conversion(sim, model):
    rng = np.random.default_rng(12)
    for _ in range(50):
        sim.reset(random_configuration(model, rng, scale=1.0), rng.normal(size=18))
        q, v = sim.state()
        q_ref, v_ref = mujoco_to_pin(sim.data.qpos, sim.data.qvel)
        np.testing.assert_array_equal(q, q_ref)
        np.testing.assert_allclose(v, v_ref, rtol=0.0, atol=1e-14)
    assert q is not sim.state()[0]  # new arrays every call


def test_a_diverged_state_raises_as_the_conversion_does():
    sim = Go2Simulator()
    sim.data.qvel[7] = np.nan
    with pytest.raises(NonFiniteError, match=r"qvel: non-finite value at index \[7\]"):
        sim.state()


def test_physics_is_bit_identical_to_mujoco_stepped_by_hand(description):
    """The drivers' law and a push written into a bare MuJoCo copy, one mj_step at a time,
    give the same bits as the simulator's two-step control periods."""
    sim = Go2Simulator(actuator_order=UNITREE_SDK_JOINT_NAMES)
    model = sim.spec.compile()
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = sim.data.qpos, sim.data.qvel
    mujoco.mj_forward(model, data)
    pd = JointPdController(description.pose("standing"))
    base = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base")
    push_end = -1.0
    for tick in range(300):
        q, v = sim.state()
        command = MotorCommand(q_des=description.pose("standing")[7:], dq_des=np.zeros(12),
                               kp=np.full(12, 30.0), kd=np.full(12, 1.0),
                               tau_ff=pd.compute(q, v) * 0.5)
        if tick == 100:  # a push that ends inside a control period
            sim.apply_force([0.0, 40.0, 0.0], 0.0105)
            push_end = data.time + 0.0105
        sdk = command.reordered(sim.actuator_map.index)
        data.ctrl[:] = sdk.tau_ff + sdk.kp * sdk.q_des + sdk.kd * sdk.dq_des
        model.actuator_biasprm[:, 1] = -sdk.kp
        model.actuator_biasprm[:, 2] = -sdk.kd
        for _ in range(2):
            data.xfrc_applied[:] = 0.0
            if push_end > data.time + 1e-12:
                data.xfrc_applied[base, 1] = 40.0
            mujoco.mj_step(model, data)
        sim.step_command(command, n_steps=2)
        np.testing.assert_array_equal(sim.data.qpos, data.qpos)
        np.testing.assert_array_equal(sim.data.qvel, data.qvel)
    assert push_end > 0.1 and not sim.data.xfrc_applied.any()


def test_foot_arrays_are_the_dicts_in_leg_order(sim, description):
    sim.reset("standing")
    pd = JointPdController(description.pose("standing"))
    for _ in range(50):
        sim.step(pd.compute(*sim.state()))
    forces, positions = sim.foot_contact_forces(), sim.foot_positions()
    sliding = sim.foot_sliding_velocities()
    assert list(forces) == list(LEGS)
    np.testing.assert_array_equal(sim.foot_contact_force_array(), [forces[leg] for leg in LEGS])
    np.testing.assert_array_equal(sim.foot_position_array(), [positions[leg] for leg in LEGS])
    out = np.full((4, 2), np.nan)
    assert sim.foot_sliding_velocity_array(out) is out
    np.testing.assert_array_equal(out, [sliding[leg] for leg in LEGS])
    assert min(f[2] for f in forces.values()) > 5.0


def test_step_command_takes_the_descriptions_order_only():
    sim = Go2Simulator(actuator_order=UNITREE_SDK_JOINT_NAMES)
    tau = np.arange(12.0) - 6.0
    sim.step_command(MotorCommand.pure_torque(tau))
    fr_hip = UNITREE_SDK_JOINT_NAMES.index("FR_hip_joint")
    assert sim.data.ctrl[fr_hip] == tau[JOINT_NAMES.index("FR_hip_joint")]  # by name
    in_plant_order = MotorCommand.pure_torque(tau).reordered(sim.actuator_map.index)
    with pytest.raises(OrderMismatchError) as error:
        sim.step_command(in_plant_order)
    assert str(error.value) == (
        "Go2Simulator.step_command(command): in the Unitree SDK's joint order (by leg FR, FL, "
        "RR, RL), expected the description's joint order (by leg FL, FR, RL, RR): a command in "
        "the plant's actuator order goes to step_actuator_command")
