"""Unitree SDK adapter: order by name, stop sentinels, quaternion order, frames, round trips."""

from types import SimpleNamespace

import numpy as np
import pinocchio as pin
import pytest

from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES
from wbc.model.joint_map import JointMap
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_low_state import SdkLowState, sensor_record_from_message
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.unitree_sdk import (
    MODE_ENABLE,
    POS_STOP_F,
    SDK_MOTOR_SLOTS,
    VEL_STOP_F,
)

S = np.sqrt(0.5)  # cos(45 deg) = sin(45 deg)


def random_command(rng: np.random.Generator, zero_gain_fraction: float = 0.0) -> MotorCommand:
    kp = rng.uniform(1.0, 60.0, 12)
    kd = rng.uniform(0.5, 5.0, 12)
    kp[rng.random(12) < zero_gain_fraction] = 0.0
    kd[rng.random(12) < zero_gain_fraction] = 0.0
    return MotorCommand(q_des=rng.uniform(-2.0, 2.0, 12), dq_des=rng.normal(size=12), kp=kp,
                        kd=kd, tau_ff=rng.uniform(-20.0, 20.0, 12))


def random_state(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    quat = rng.normal(size=4)
    q = np.concatenate([rng.normal(size=3), quat / np.linalg.norm(quat),
                        rng.uniform(-2.0, 2.0, 12)])
    return q, rng.normal(size=18)


def rotation(q: np.ndarray) -> np.ndarray:
    """R_world_base of a Pinocchio configuration, computed by Pinocchio itself."""
    x, y, z, w = q[3:7]
    return pin.Quaternion(w, x, y, z).toRotationMatrix()


def motor_fields(**changes) -> dict:
    return {"mode": np.ones(12), "q": np.zeros(12), "dq": np.zeros(12), "tau": np.zeros(12),
            "kp": np.full(12, 20.0), "kd": np.ones(12), **changes}


def state_fields(**changes) -> dict:
    return {"imu_quaternion_wxyz": [1.0, 0.0, 0.0, 0.0], "gyroscope_rad_s": np.zeros(3),
            "accelerometer_m_s2": [0.0, 0.0, 9.81], "q": np.zeros(12), "dq": np.zeros(12),
            "tau_est": np.zeros(12), "foot_force": np.zeros(4), **changes}


# --- motor command -------------------------------------------------------------------------


def test_command_round_trip_random():
    rng = np.random.default_rng(0)
    for _ in range(50):
        cmd = random_command(rng)
        back = SdkMotorCommand.from_control_output(cmd).to_motor_command()
        assert type(back) is MotorCommand
        for name in ("q_des", "dq_des", "kp", "kd", "tau_ff"):
            np.testing.assert_array_equal(getattr(back, name), getattr(cmd, name), err_msg=name)


def test_command_round_trip_with_zero_gains():
    """Exact without sentinels; with them, only the targets a zero gain ignores become 0."""
    rng = np.random.default_rng(1)
    for _ in range(50):
        cmd = random_command(rng, zero_gain_fraction=0.4)
        plain = SdkMotorCommand.from_control_output(cmd, use_stop_sentinels=False)
        back = plain.to_motor_command()
        for name in ("q_des", "dq_des", "kp", "kd", "tau_ff"):
            np.testing.assert_array_equal(getattr(back, name), getattr(cmd, name), err_msg=name)
        back = SdkMotorCommand.from_control_output(cmd).to_motor_command()
        np.testing.assert_array_equal(back.q_des, np.where(cmd.kp == 0.0, 0.0, cmd.q_des))
        np.testing.assert_array_equal(back.dq_des, np.where(cmd.kd == 0.0, 0.0, cmd.dq_des))
        for name in ("kp", "kd", "tau_ff"):
            np.testing.assert_array_equal(getattr(back, name), getattr(cmd, name), err_msg=name)


def test_command_order_is_by_name():
    values = np.arange(12.0)  # value i belongs to JOINT_NAMES[i]
    cmd = MotorCommand(q_des=values, dq_des=values + 100, kp=values + 200, kd=values + 300,
                       tau_ff=values + 400)
    sdk = SdkMotorCommand.from_control_output(cmd)
    assert UNITREE_SDK_JOINT_NAMES[0] == "FR_hip_joint"
    assert sdk.q[0] == JOINT_NAMES.index("FR_hip_joint") == 3
    assert sdk.tau[0] == 403.0
    assert sdk.kp[3] == 200.0 + JOINT_NAMES.index("FL_hip_joint") == 200.0
    assert sdk.dq[8] == 100.0 + JOINT_NAMES.index("RR_calf_joint") == 111.0
    assert sdk.kd[10] == 300.0 + JOINT_NAMES.index("RL_thigh_joint") == 307.0
    for k, name in enumerate(UNITREE_SDK_JOINT_NAMES):
        assert sdk.tau[k] == 400.0 + JOINT_NAMES.index(name)


def test_sentinels_exactly_where_gains_are_zero():
    rng = np.random.default_rng(2)
    for _ in range(20):
        cmd = random_command(rng, zero_gain_fraction=0.5)
        sdk = SdkMotorCommand.from_control_output(cmd)
        kp_sdk = JointMap.unitree_sdk().to_other(cmd.kp)
        kd_sdk = JointMap.unitree_sdk().to_other(cmd.kd)
        np.testing.assert_array_equal(sdk.q == POS_STOP_F, kp_sdk == 0.0)
        np.testing.assert_array_equal(sdk.dq == VEL_STOP_F, kd_sdk == 0.0)
        np.testing.assert_array_equal(sdk.mode, np.full(12, MODE_ENABLE))


def test_pure_torque_is_all_sentinels():
    tau = np.linspace(-5.0, 5.0, 12)
    sdk = SdkMotorCommand.from_control_output(MotorCommand.pure_torque(tau))
    np.testing.assert_array_equal(sdk.q, np.full(12, POS_STOP_F))
    np.testing.assert_array_equal(sdk.dq, np.full(12, VEL_STOP_F))
    np.testing.assert_array_equal(sdk.tau, JointMap.unitree_sdk().to_other(tau))
    assert sdk.mode.dtype == np.uint8


def test_driver_torque_matches_description_command():
    """The SDK driver law on the reordered command gives the description command's torques."""
    rng = np.random.default_rng(3)
    sdk_map = JointMap.unitree_sdk()
    for fraction in (0.0, 0.5, 1.0):
        cmd = random_command(rng, zero_gain_fraction=fraction)
        q, dq = rng.uniform(-2.0, 2.0, 12), rng.normal(size=12)
        sdk = SdkMotorCommand.from_control_output(cmd)
        np.testing.assert_allclose(sdk.torque_at(sdk_map.to_other(q), sdk_map.to_other(dq)),
                                   sdk_map.to_other(cmd.torque_at(q, dq)), atol=1e-12)


def test_control_output_is_accepted():
    rng = np.random.default_rng(4)
    cmd = random_command(rng)
    out = ControlOutput(q_des=cmd.q_des, dq_des=cmd.dq_des, kp=cmd.kp, kd=cmd.kd,
                        tau_ff=cmd.tau_ff, tau=cmd.tau_ff, qdd=np.zeros(18),
                        forces=np.zeros((4, 3)), status=ControlStatus.OK)
    np.testing.assert_array_equal(SdkMotorCommand.from_control_output(out).tau,
                                  JointMap.unitree_sdk().to_other(cmd.tau_ff))


def test_stopped_motor_comes_back_as_zero_torque():
    sdk = SdkMotorCommand(**motor_fields(mode=[0] + [1] * 11, q=np.full(12, 0.3),
                                         tau=np.full(12, 2.0)))
    back = sdk.to_motor_command()
    fr_hip = JOINT_NAMES.index("FR_hip_joint")  # SDK slot 0
    for name in ("q_des", "dq_des", "kp", "kd", "tau_ff"):
        assert getattr(back, name)[fr_hip] == 0.0, name
    assert back.q_des[JOINT_NAMES.index("FL_hip_joint")] == 0.3
    assert sdk.torque_at(np.zeros(12), np.zeros(12))[0] == 0.0


def test_float32_sentinel_is_recognised():
    """A message stores float32: the sentinel read back from one still means 'unused'."""
    sdk = SdkMotorCommand(**motor_fields(q=np.full(12, np.float32(POS_STOP_F)),
                                         dq=np.full(12, np.float32(VEL_STOP_F)),
                                         kp=np.zeros(12), kd=np.zeros(12)))
    back = sdk.to_motor_command()
    np.testing.assert_array_equal(back.q_des, np.zeros(12))
    np.testing.assert_array_equal(back.dq_des, np.zeros(12))


def test_as_20_slots_and_write_to():
    rng = np.random.default_rng(5)
    sdk = SdkMotorCommand.from_control_output(random_command(rng, zero_gain_fraction=0.3))
    slots = sdk.as_20_slots()
    assert set(slots) == {"mode", "q", "dq", "tau", "kp", "kd"}
    for name, values in slots.items():
        assert values.shape == (SDK_MOTOR_SLOTS,), name
        np.testing.assert_array_equal(values[:12], getattr(sdk, name), err_msg=name)
    # Slots 12 to 19 (no GO2 motor) idle as the SDK's examples send them: enabled, the stop
    # sentinels as targets, no gains, no torque.
    idle = {"mode": MODE_ENABLE, "q": POS_STOP_F, "dq": VEL_STOP_F, "tau": 0.0, "kp": 0.0,
            "kd": 0.0}
    for name, value in idle.items():
        np.testing.assert_array_equal(slots[name][12:], np.full(8, value), err_msg=name)
    assert slots["mode"].dtype == np.uint8

    low_cmd = SimpleNamespace(motor_cmd=[SimpleNamespace() for _ in range(SDK_MOTOR_SLOTS)])
    sdk.write_to(low_cmd)
    for k, motor in enumerate(low_cmd.motor_cmd):
        assert type(motor.mode) is int and type(motor.q) is float
        assert (motor.mode, motor.q, motor.dq, motor.tau, motor.kp, motor.kd) == tuple(
            slots[name][k] for name in ("mode", "q", "dq", "tau", "kp", "kd"))
    with pytest.raises(ConfigurationError, match="low_cmd: expected a LowCmd_ with a motor_cmd "
                                                 "list of 20 entries, received SimpleNamespace"):
        sdk.write_to(SimpleNamespace(motor_cmd=[]))


def test_bad_commands_name_the_field():
    with pytest.raises(ConfigurationError, match=r"^q: expected an array of shape \(12,\), "
                                                 r"received shape \(11,\)"):
        SdkMotorCommand(**motor_fields(q=np.zeros(11)))
    with pytest.raises(NonFiniteError, match=r"^tau: non-finite value at index \[2\]"):
        SdkMotorCommand(**motor_fields(tau=[0.0, 0.0, np.nan] + [0.0] * 9))
    with pytest.raises(ConfigurationError, match=r"^kp: expected gains >= 0, received \[-1.0\] "
                                                 r"at 4 \(FL_thigh_joint\)"):
        SdkMotorCommand(**motor_fields(kp=[20.0] * 4 + [-1.0] + [20.0] * 7))
    with pytest.raises(ConfigurationError, match=r"^mode: expected 0x00 \(stop\) or 0x01 "
                                                 r"\(enable\), received \[2.0\] at slots 11 "
                                                 r"\(RL_calf_joint\)"):
        SdkMotorCommand(**motor_fields(mode=[1] * 11 + [2]))
    with pytest.raises(ConfigurationError, match=r"^q: the stop sentinel 2.146e\+09 with kp > 0 "
                                                 r"at slots 0 \(FR_hip_joint\)"):
        SdkMotorCommand(**motor_fields(q=[POS_STOP_F] + [0.0] * 11))
    with pytest.raises(ConfigurationError, match=r"^dq: the stop sentinel 16000 with kd > 0"):
        SdkMotorCommand(**motor_fields(dq=[VEL_STOP_F] * 12))


def test_bad_control_output_names_the_field():
    rng = np.random.default_rng(6)
    cmd = random_command(rng)
    cmd.kp[JOINT_NAMES.index("RR_hip_joint")] = -3.0
    with pytest.raises(ConfigurationError, match=r"^cmd.kp: expected gains >= 0, received "
                                                 r"\[-3.0\] at 9 \(RR_hip_joint\)"):
        SdkMotorCommand.from_control_output(cmd)
    cmd = random_command(rng)
    cmd.q_des = np.zeros(13)
    with pytest.raises(ConfigurationError, match=r"^cmd.q_des: expected an array of shape "
                                                 r"\(12,\), received shape \(13,\)"):
        SdkMotorCommand.from_control_output(cmd)
    cmd = random_command(rng)
    cmd.dq_des[0] = np.inf
    with pytest.raises(NonFiniteError, match=r"^cmd.dq_des: non-finite value at index \[0\]"):
        SdkMotorCommand.from_control_output(cmd)


# --- low state -----------------------------------------------------------------------------


def test_state_round_trip_random():
    rng = np.random.default_rng(7)
    for _ in range(50):
        q, v = random_state(rng)
        state = SdkLowState.from_pinocchio(q, v)
        q2, v2 = state.to_pinocchio(base_position=q[:3],
                                    base_linear_velocity_world=rotation(q) @ v[:3])
        np.testing.assert_allclose(q2, q, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(v2, v, rtol=0.0, atol=1e-12)


def test_state_order_is_by_name():
    q = np.zeros(19)
    q[6] = 1.0
    q[7:] = np.arange(12.0)  # value i belongs to JOINT_NAMES[i]
    v = np.zeros(18)
    v[6:] = 100.0 + np.arange(12.0)
    tau = 200.0 + np.arange(12.0)
    state = SdkLowState.from_pinocchio(q, v, tau_est=tau)
    assert state.q[0] == JOINT_NAMES.index("FR_hip_joint") == 3  # SDK slot 0: FR hip
    assert state.q[3] == JOINT_NAMES.index("FL_hip_joint") == 0
    assert state.dq[8] == 100.0 + JOINT_NAMES.index("RR_calf_joint") == 111.0
    assert state.tau_est[11] == 200.0 + JOINT_NAMES.index("RL_calf_joint") == 208.0
    np.testing.assert_array_equal(state.joint_torques(), tau)

    sdk_values = np.arange(12.0)  # value k belongs to UNITREE_SDK_JOINT_NAMES[k]
    q2, v2 = SdkLowState(**state_fields(q=sdk_values, dq=-sdk_values)).to_pinocchio()
    for name in ("FR_hip_joint", "FL_calf_joint", "RR_thigh_joint", "RL_hip_joint"):
        assert q2[7 + JOINT_NAMES.index(name)] == UNITREE_SDK_JOINT_NAMES.index(name), name
        assert v2[6 + JOINT_NAMES.index(name)] == -UNITREE_SDK_JOINT_NAMES.index(name), name


def test_quaternion_order_on_a_known_rotation():
    """90 deg about z: (w, x, y, z) = (s, 0, 0, s) in the SDK, (0, 0, s, s) in Pinocchio."""
    state = SdkLowState(**state_fields(imu_quaternion_wxyz=[S, 0.0, 0.0, S]))
    q, _ = state.to_pinocchio()
    np.testing.assert_allclose(q[3:7], [0.0, 0.0, S, S], atol=1e-15)
    np.testing.assert_allclose(rotation(q), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(SdkLowState.from_pinocchio(q, np.zeros(18)).imu_quaternion_wxyz,
                               [S, 0.0, 0.0, S], atol=1e-15)


def test_quaternion_is_normalised():
    q, _ = SdkLowState(**state_fields(imu_quaternion_wxyz=[2.0, 0.0, 0.0, 2.0])).to_pinocchio()
    np.testing.assert_allclose(q[3:7], [0.0, 0.0, S, S], atol=1e-15)


def test_world_linear_velocity_rotated_into_base_frame():
    """Yawed 90 deg left, moving along world x is moving towards the base's right (-y)."""
    gyro = np.array([0.1, -0.2, 0.3])
    state = SdkLowState(**state_fields(imu_quaternion_wxyz=[S, 0.0, 0.0, S], gyroscope_rad_s=gyro))
    q, v = state.to_pinocchio(base_position=[1.0, 2.0, 0.3],
                              base_linear_velocity_world=[1.0, 0.0, 0.5])
    np.testing.assert_allclose(v[:3], [0.0, -1.0, 0.5], atol=1e-15)
    np.testing.assert_array_equal(v[3:6], gyro)  # already in the base frame
    np.testing.assert_array_equal(q[:3], [1.0, 2.0, 0.3])
    _, v0 = state.to_pinocchio()
    np.testing.assert_array_equal(v0[:3], np.zeros(3))


def test_default_accelerometer_is_gravity_in_base_frame():
    rng = np.random.default_rng(8)
    q, v = random_state(rng)
    state = SdkLowState.from_pinocchio(q, v)
    np.testing.assert_allclose(state.accelerometer_m_s2, rotation(q).T @ [0.0, 0.0, 9.81],
                               atol=1e-12)
    q[3:7] = [0.0, 0.0, 0.0, 1.0]
    np.testing.assert_allclose(SdkLowState.from_pinocchio(q, v).accelerometer_m_s2,
                               [0.0, 0.0, 9.81], atol=1e-15)
    given = SdkLowState.from_pinocchio(q, v, accelerometer_m_s2=[1.0, 2.0, 3.0])
    np.testing.assert_array_equal(given.accelerometer_m_s2, [1.0, 2.0, 3.0])


def test_foot_forces_by_leg():
    state = SdkLowState(**state_fields(foot_force=[10, 20, 30, 40]))  # FR, FL, RR, RL
    forces = state.foot_forces_by_leg()
    assert list(forces) == list(LEGS)
    assert forces == {"FL": 20.0, "FR": 10.0, "RL": 40.0, "RR": 30.0}
    q = np.zeros(19)
    q[6] = 1.0
    again = SdkLowState.from_pinocchio(q, np.zeros(18), foot_force_by_leg=forces)
    np.testing.assert_array_equal(again.foot_force, [10, 20, 30, 40])


def test_from_message():
    rng = np.random.default_rng(9)
    motors = [SimpleNamespace(q=rng.normal(), dq=rng.normal(), tau_est=rng.normal(), ddq=0.0)
              for _ in range(SDK_MOTOR_SLOTS)]
    msg = SimpleNamespace(
        imu_state=SimpleNamespace(quaternion=[S, 0.0, 0.0, S], gyroscope=[0.1, 0.2, 0.3],
                                  accelerometer=[0.0, 0.0, 9.8], rpy=[0.0, 0.0, np.pi / 2]),
        motor_state=motors, foot_force=[1, 2, 3, 4])
    state = SdkLowState.from_message(msg)
    np.testing.assert_array_equal(state.imu_quaternion_wxyz, [S, 0.0, 0.0, S])
    np.testing.assert_array_equal(state.gyroscope_rad_s, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(state.q, [m.q for m in motors[:12]])
    np.testing.assert_array_equal(state.tau_est, [m.tau_est for m in motors[:12]])
    np.testing.assert_array_equal(state.foot_force, [1, 2, 3, 4])
    del msg.imu_state.gyroscope
    with pytest.raises(ConfigurationError, match="^low_state: expected a LowState_ .* received "
                                                 "SimpleNamespace: .*gyroscope"):
        SdkLowState.from_message(msg)


def test_to_message_is_read_back_as_it_was():
    rng = np.random.default_rng(4)
    state = SdkLowState(**state_fields(
        imu_quaternion_wxyz=[S, 0.0, S, 0.0], gyroscope_rad_s=rng.normal(size=3),
        q=rng.normal(size=12), dq=rng.normal(size=12), tau_est=rng.normal(size=12),
        foot_force=[10, 20, 30, 40]), tick=77)
    msg = state.to_message()
    assert len(msg.motor_state) == SDK_MOTOR_SLOTS
    assert all(m.q == 0.0 for m in msg.motor_state[12:])
    back = SdkLowState.from_message(msg)
    for name in ("imu_quaternion_wxyz", "gyroscope_rad_s", "accelerometer_m_s2", "q", "dq",
                 "tau_est", "foot_force"):
        np.testing.assert_array_equal(getattr(back, name), getattr(state, name), err_msg=name)
    assert back.tick == 77
    record = sensor_record_from_message(msg)
    np.testing.assert_array_equal(record.q, state.sensor_record().q)


def test_bad_states_name_the_field():
    with pytest.raises(ConfigurationError, match=r"^imu_quaternion_wxyz: expected a unit "
                                                 r"quaternion \(w, x, y, z\), received "
                                                 r"\[0.0, 0.0, 0.0, 0.0\] \(norm 0"):
        SdkLowState(**state_fields(imu_quaternion_wxyz=np.zeros(4)))
    with pytest.raises(NonFiniteError, match=r"^imu_quaternion_wxyz: non-finite value at "
                                             r"index \[0\]"):
        SdkLowState(**state_fields(imu_quaternion_wxyz=[np.nan, 0.0, 0.0, 1.0]))
    with pytest.raises(NonFiniteError, match=r"^gyroscope_rad_s: non-finite value at index \[1\]"):
        SdkLowState(**state_fields(gyroscope_rad_s=[0.0, np.nan, 0.0]))
    with pytest.raises(ConfigurationError, match=r"^q: expected an array of shape \(12,\), "
                                                 r"received shape \(19,\)"):
        SdkLowState(**state_fields(q=np.zeros(19)))
    with pytest.raises(ConfigurationError, match=r"^foot_force: expected an array of shape "
                                                 r"\(4,\), received shape \(3,\)"):
        SdkLowState(**state_fields(foot_force=[1, 2, 3]))
    state = SdkLowState(**state_fields())
    with pytest.raises(ConfigurationError, match=r"^base_position: expected an array of shape "
                                                 r"\(3,\), received shape \(2,\)"):
        state.to_pinocchio(base_position=[0.0, 0.0])
    with pytest.raises(NonFiniteError, match=r"^base_linear_velocity_world: non-finite"):
        state.to_pinocchio(base_linear_velocity_world=[0.0, np.inf, 0.0])


def test_bad_pinocchio_inputs_name_the_field():
    q = np.zeros(19)
    with pytest.raises(ConfigurationError, match=r"^q\[3:7\]: expected a unit quaternion "
                                                 r"\(x, y, z, w\), received \[0.0, 0.0, 0.0, "
                                                 r"0.0\]"):
        SdkLowState.from_pinocchio(q, np.zeros(18))
    q[6] = 1.0
    with pytest.raises(ConfigurationError, match=r"^v: expected an array of shape \(18,\)"):
        SdkLowState.from_pinocchio(q, np.zeros(19))
    with pytest.raises(ConfigurationError, match=r"^tau_est: expected an array of shape \(12,\)"):
        SdkLowState.from_pinocchio(q, np.zeros(18), tau_est=np.zeros(4))
    with pytest.raises(ConfigurationError, match=r"^foot_force_by_leg: missing legs \['RR'\]; "
                                                 r"expected one value for each of FL, FR, RL, RR"):
        SdkLowState.from_pinocchio(q, np.zeros(18), foot_force_by_leg={"FL": 1, "FR": 1, "RL": 1})
    with pytest.raises(UnknownNameError, match="unknown leg 'LF'; valid legs: FL, FR, RL, RR"):
        SdkLowState.from_pinocchio(q, np.zeros(18), foot_force_by_leg={"LF": 1})
