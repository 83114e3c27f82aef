"""The simulated GO2's sensors: presets, the truth through the exact preset, noise, the IMU's
attitude filter, foot counts, seeds, and joint and leg orders."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import sim.sensors as sensors_module
from actions.robot.robot_interface import MappedRobot
from sim.mujoco_robot import MujocoRobot
from sim.sensors import (
    SENSOR_PRESETS,
    PlantReading,
    RecordArrays,
    SensorDrift,
    SensorModel,
    SensorSites,
    SimulatedSensors,
    _sample,
    sampler_params,
)
from sim.simulator import Go2Simulator
from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError
from wbc.model.description import LEGS, UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord


def held(sim: Go2Simulator) -> MotorCommand:
    """A stiff joint PD around the standing pose: the robot stands still."""
    pose = sim.description.pose("standing")[7:]
    return MotorCommand(q_des=pose, dq_des=np.zeros(12), kp=np.full(12, 80.0),
                        kd=np.full(12, 3.0), tau_ff=np.zeros(12))


def standing_sim() -> Go2Simulator:
    sim = Go2Simulator()
    for _ in range(300):  # the spawned robot settles
        sim.step_command(held(sim))
    return sim


def test_presets_and_changes_by_name():
    assert set(SENSOR_PRESETS) == {"go2", "exact"}
    go2 = SensorModel.preset("go2")
    assert go2 == SensorModel() and not go2.is_exact and SENSOR_PRESETS["exact"].is_exact
    changed = go2.with_params(gyro_noise_rad_s=0.01, foot_force_integer=False)
    assert changed.gyro_noise_rad_s == 0.01 and changed.name == (
        "go2 + gyro_noise_rad_s=0.01, foot_force_integer=False")
    assert "attitude filter 5 s" in go2.describe()
    assert SENSOR_PRESETS["exact"].describe() == "sensors exact (the true state, no noise)"


def test_bad_sensor_parameters_name_the_field():
    with pytest.raises(UnknownNameError, match=r"^unknown sensor preset 'noisy'; valid sensor "
                                               r"presets: go2, exact$"):
        SensorModel.preset("noisy")
    with pytest.raises(UnknownNameError, match=r"^unknown sensor parameter 'gyro_noise'; valid "
                                               r"sensor parameters: gyro_noise_rad_s, "):
        SensorModel().with_params(gyro_noise=0.1)
    with pytest.raises(UnknownNameError, match=r"^unknown sensor parameter 'gyro'"):
        SensorModel(gyro=1.0)  # type: ignore[call-arg]
    with pytest.raises(NonFiniteError, match=r"^accel_noise_m_s2: expected a finite number, "
                                             r"received nan$"):
        SensorModel().with_params(accel_noise_m_s2=math.nan)
    with pytest.raises(ConfigurationError, match=r"^gyro_noise_rad_s: expected a value in "
                                                 r"\[0, 1\], received -0.1$"):
        SensorModel(gyro_noise_rad_s=-0.1)
    with pytest.raises(ConfigurationError, match=r"^foot_force_full_scale: expected more than "
                                                 r"foot_force_offset \(10\), received 5$"):
        SensorModel(foot_force_full_scale=5.0)
    with pytest.raises(ConfigurationError, match=r"^sensors: expected a SensorModel or a preset"):
        SimulatedSensors(Go2Simulator(), 3)  # type: ignore[arg-type]


def test_the_exact_preset_reports_the_true_state():
    sim = standing_sim()
    sensors = SimulatedSensors(sim, "exact")
    record = SensorRecord.zeros()
    sensors.sample(record)
    sim.step_command(held(sim))
    sensors.sample(record)
    np.testing.assert_array_equal(record.imu_quaternion_wxyz, sim.data.qpos[3:7])
    np.testing.assert_array_equal(record.gyroscope_rad_s, sim.data.qvel[3:6])
    np.testing.assert_array_equal(record.q, sim.data.qpos[7:])
    np.testing.assert_array_equal(record.dq, sim.data.qvel[6:])
    np.testing.assert_array_equal(record.tau_est, sim.data.actuator_force)
    np.testing.assert_allclose(record.foot_force, 10.0 + 2.5 * sim.foot_normal_forces())
    np.testing.assert_allclose(sim.foot_normal_forces(), sim.foot_contact_force_array()[:, 2],
                               rtol=1e-9)
    assert record.tick == 2 and record.stamp_s == sim.time_s


def test_the_accelerometer_reads_the_imu_sites_specific_force_over_the_period():
    """Checked against MuJoCo's own velocity of the URDF's ``imu`` body, before and after."""
    sim = Go2Simulator()
    sensors = SimulatedSensors(sim, "exact")
    record = SensorRecord.zeros()
    imu = mujoco.mj_name2id(sim.model, mujoco.mjtObj.mjOBJ_BODY, "imu")
    velocity = np.zeros(6)

    def imu_velocity() -> np.ndarray:
        mujoco.mj_forward(sim.model, sim.data)  # after a step, MuJoCo's velocities are stale
        mujoco.mj_objectVelocity(sim.model, sim.data, mujoco.mjtObj.mjOBJ_BODY, imu, velocity,
                                 0)  # world frame: (angular, linear)
        return velocity[3:].copy()

    sensors.sample(record)
    for _ in range(40):  # the spawned robot drops onto its feet and bounces: accelerations
        before = imu_velocity()
        sim.step_command(held(sim))
        sensors.sample(record)
        rotation = sim.data.xmat[imu].reshape(3, 3)
        expected = rotation.T @ ((imu_velocity() - before) / 1e-3 + [0.0, 0.0, 9.81])
        np.testing.assert_allclose(record.accelerometer_m_s2, expected, atol=1e-9)


def test_noise_has_the_preset_spread_and_the_seed_repeats_it():
    sim = standing_sim()
    exact, noisy = SimulatedSensors(sim, "exact"), SimulatedSensors(sim, "go2", seed=4)
    twin = SimulatedSensors(sim, "go2", seed=4)
    a, b, c = SensorRecord.zeros(), SensorRecord.zeros(), SensorRecord.zeros()
    gyro, dq, joints, twin_equal = [], [], [], True
    for _ in range(2000):
        sim.step_command(held(sim))
        exact.sample(a)
        noisy.sample(b)
        twin.sample(c)
        gyro.append(b.gyroscope_rad_s - a.gyroscope_rad_s)
        dq.append(b.dq - a.dq)
        joints.append(b.q)
        twin_equal &= bool(np.array_equal(b.as_dict()["q"], c.as_dict()["q"]))
    gyro = np.array(gyro)
    # White noise around the bias: its spread is the preset's 0.004 rad/s.
    np.testing.assert_allclose(np.std(gyro, axis=0), 0.004, rtol=0.1)
    np.testing.assert_allclose(np.mean(gyro, axis=0), noisy.gyro_bias, atol=3e-4)
    np.testing.assert_allclose(np.std(np.array(dq)), 0.02, rtol=0.1)
    # Encoders: multiples of their 3e-5 rad step.
    steps = np.array(joints) / 3e-5
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    assert twin_equal
    other = SimulatedSensors(sim, "go2", seed=5)
    other.sample(c)
    assert not np.array_equal(other.gyro_bias, noisy.gyro_bias)


def test_the_noise_block_size_changes_no_value_and_a_reset_simulator_is_sampled(monkeypatch):
    # The noise is drawn a few samples at a time (no 0.4 ms stall every 1024 samples): the
    # same seed gives the same values in the same order as one large block would.
    def records(block: int, samples: int = 1100) -> list[np.ndarray]:
        monkeypatch.setattr(sensors_module, "_NOISE_BLOCK", block)
        sim = Go2Simulator()
        sensors, record, out = SimulatedSensors(sim, "go2", seed=7), SensorRecord.zeros(), []
        for _ in range(samples):
            sim.step(np.zeros(12))
            sensors.sample(record)
            out.append(np.concatenate([record.q, record.dq, record.tau_est,
                                       record.gyroscope_rad_s, record.accelerometer_m_s2,
                                       record.imu_quaternion_wxyz, record.foot_force]))
        sim.reset("standing")  # time goes back: the sensors start again from their seed
        sensors.sample(record)
        assert sensors.ticks == 1
        return out

    assert np.array_equal(records(1024), records(16))
    assert np.array_equal(records(1024), records(1))


def attitude_errors(accel_bias, seconds: float = 20.0, tilt_start_deg: float = 0.0):
    """The simulated IMU's attitude filter on a level robot at rest: its roll error [deg]
    every 2 s, with a constant accelerometer bias (and a start tilted about x)."""
    params = sampler_params(SensorModel.preset("exact").with_params(attitude_time_constant_s=5.0))
    qpos = np.zeros(19)
    qpos[3] = 1.0
    half = math.radians(tilt_start_deg) / 2
    attitude = np.array([math.cos(half), math.sin(half), 0.0, 0.0])
    outputs = [np.zeros(4), np.zeros(3), np.zeros(3), np.zeros(12), np.zeros(12), np.zeros(12),
               np.zeros(4)]
    joints = np.arange(7, 19, dtype=np.intp)
    rolls = []
    for k in range(int(seconds * 1000) + 1):
        _sample(PlantReading(qpos, np.zeros(18), np.zeros(12), np.zeros(4), 1e-3, k > 0),
                SensorSites(joints, joints - 1, np.arange(4, dtype=np.intp), np.zeros(3)),
                params, SensorDrift(np.zeros(3), np.zeros(3), np.asarray(accel_bias, float),
                                    attitude, np.zeros(3)),
                np.zeros(52), RecordArrays(*outputs))
        if k % 2000 == 0:
            w, x = outputs[0][0], outputs[0][1]
            rolls.append(math.degrees(2 * math.atan2(x, w)))
    return rolls


def test_the_imu_attitude_filter_settles_on_the_accelerometer_bias_and_corrects_a_tilt():
    # A 0.01 m/s^2 bias on y reads as a roll of 0.058 deg: the filter settles there (its
    # integral term overshoots by about 15 %) rather than running away.
    rolls = attitude_errors([0.0, 0.01, 0.0])
    expected = math.degrees(math.atan2(0.01, 9.81))
    assert rolls[-1] == pytest.approx(expected, abs=0.012)
    assert max(abs(r) for r in rolls) < 1.25 * abs(expected)
    # A filter started 2 deg off comes back to level within a few time constants.
    rolls = attitude_errors([0.0, 0.0, 0.0], seconds=30.0, tilt_start_deg=2.0)
    assert rolls[0] == pytest.approx(2.0, abs=1e-3) and abs(rolls[-1]) < 0.05


def test_the_imu_starts_settled_on_its_biased_accelerometer():
    """A real IMU's filter has run since power-up: it starts tilted by the bias over g."""
    sim = Go2Simulator()  # level
    sensors = SimulatedSensors(sim, "go2", seed=2)
    record = SensorRecord.zeros()
    sensors.sample(record)
    _, x, y, _ = record.imu_quaternion_wxyz
    bias = sensors.accel_bias
    assert math.degrees(2 * x) == pytest.approx(math.degrees(bias[1] / 9.81), abs=2e-3)
    assert math.degrees(2 * y) == pytest.approx(-math.degrees(bias[0] / 9.81), abs=2e-3)
    assert abs(bias[:2]).max() > 1e-3  # this seed's bias is large enough to show it


def test_a_robot_in_the_sdk_order_reports_in_its_orders_and_is_mapped_by_name():
    mapped = []
    for order in (None, UNITREE_SDK_JOINT_NAMES):
        sim = Go2Simulator(actuator_order=order)
        robot = MujocoRobot(sim, sensors="exact")
        for _ in range(50):  # a command in the plant's own order: its orders say so
            robot.write_command(MotorCommand.pure_torque(np.zeros(12), orders=robot.orders))
        mapped.append(MappedRobot(robot).read_sensors().copy())
        if order is not None:
            assert robot.leg_names == UNITREE_SDK_LEGS
            raw = robot.read_sensors()
            assert raw.q[0] == sim.data.qpos[7 + 3]  # SDK slot 0 is FR_hip: joint 3
            fr = LEGS.index("FR")
            assert raw.foot_force[0] == pytest.approx(10.0 + 2.5 * sim.foot_normal_forces()[fr])
    np.testing.assert_array_equal(mapped[0].q, mapped[1].q)
    np.testing.assert_array_equal(mapped[0].foot_force, mapped[1].foot_force)


def test_the_one_call_sample_is_the_plain_sample_bit_for_bit():
    """A record sampled again is filled by one compiled call reading its arrays from a table
    of addresses; a new record each time by the call that unboxes them: the same values,
    across the noise block's refills, and a replaced array is the one written."""
    plants = Go2Simulator(), Go2Simulator()
    one, each = SimulatedSensors(plants[0]), SimulatedSensors(plants[1])
    buffer = SensorRecord.zeros()
    for i in range(40):
        fresh = SensorRecord.zeros()
        one.sample(buffer)
        each.sample(fresh)
        for name in ("imu_quaternion_wxyz", "gyroscope_rad_s", "accelerometer_m_s2", "q", "dq",
                     "tau_est", "foot_force"):
            assert np.array_equal(getattr(buffer, name), getattr(fresh, name)), (i, name)
        assert (buffer.stamp_s, buffer.tick) == (fresh.stamp_s, fresh.tick)
        for sim in plants:
            sim.step_command(held(sim))
    assert one._program_record is buffer and each._program_record is None
    old = buffer.q
    buffer.q = np.zeros(12)
    one.sample(buffer)
    each.sample(fresh)
    assert np.array_equal(buffer.q, fresh.q) and not np.array_equal(old, buffer.q)
