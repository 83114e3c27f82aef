"""The estimators' tick as one compiled call bound to a record's arrays
(:meth:`wbc.estimation.estimator_base.EstimatorBase.update`) gives what the call that unboxes
every array gives, bit for bit, and reads a record's array that was replaced."""

from __future__ import annotations

import numpy as np
import pytest

from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from wbc.estimation.invariant_ekf import InvariantEkf
from wbc.estimation.linear_kalman_filter import LinearKalmanFilter
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord


@pytest.fixture(scope="module")
def records() -> list[SensorRecord]:
    """300 samples of the simulated GO2 held near standing, its feet pushed about."""
    sim = Go2Simulator()
    robot = MujocoRobot(sim)
    pose = sim.description.pose("standing")[7:]
    hold = MotorCommand(q_des=pose, dq_des=np.zeros(12), kp=np.full(12, 80.0),
                        kd=np.full(12, 3.0), tau_ff=np.zeros(12))
    samples = []
    for i in range(300):
        samples.append(robot.read_sensors().copy())
        hold.tau_ff[:] = 3.0 * np.sin(0.05 * i)
        sim.step_command(hold)
    return samples


@pytest.mark.parametrize("kind", [InvariantEkf, LinearKalmanFilter])
def test_the_one_call_is_the_unboxing_call_bit_for_bit(records, kind):
    buffer = records[0].copy()  # one record refilled in place, as a robot's buffer
    one, each = kind(), kind()
    one.reset(buffer)
    each.reset(records[0].copy())
    schedule = np.full(4, 120.0)
    for i, record in enumerate(records[1:]):
        buffer.copy_from(record)
        missing = i % 40 == 7  # now and then no sample: the last one's arrays stand
        a = one.update(None if missing else buffer, schedule)
        b = each.update(None if missing else record.copy(), schedule)  # a new record a tick
        assert np.array_equal(a.q, b.q) and np.array_equal(a.v, b.v), i
        assert a.flags == b.flags and np.array_equal(a.contact, b.contact)
    # The buffer runs through the one call; new records each tick through the other.
    assert one._program is not None and one._program_record is buffer
    assert each._program_record is not records[-1]
    # A record whose array is replaced is read where the array now is.
    q = buffer.q.copy()
    q[2] += 1e-3  # the calf a milliradian further
    buffer.q = q
    buffer.tick += 1  # a new sample (a repeated tick is stale: its joints are not read)
    buffer.stamp_s += 1e-3
    moved = buffer.copy()
    moved.q = q.copy()
    a = one.update(buffer, schedule)
    b = each.update(moved, schedule)
    assert np.array_equal(a.q, b.q) and a.q[7 + 2] == q[2]
    assert np.array_equal(a.v, b.v)
