"""The motor command: the driver law, reordering by name, and what a driver refuses."""

import numpy as np
import pytest

from wbc.model.description import JOINT_NAMES, UNITREE_SDK_JOINT_NAMES
from wbc.model.joint_map import JointMap
from wbc.robot_io.motor_command import (
    MotorCommand,
    command_and_torque_fine,
    within_effort_limits,
)


def random_command(rng: np.random.Generator) -> MotorCommand:
    return MotorCommand(q_des=rng.normal(size=12), dq_des=rng.normal(size=12),
                        kp=rng.uniform(0, 60, 12), kd=rng.uniform(0, 3, 12),
                        tau_ff=rng.uniform(-10, 10, 12))


def test_torque_is_the_driver_law():
    rng = np.random.default_rng(3)
    cmd = random_command(rng)
    q, dq = rng.normal(size=12), rng.normal(size=12)
    expected = [cmd.tau_ff[i] + cmd.kp[i] * (cmd.q_des[i] - q[i])
                + cmd.kd[i] * (cmd.dq_des[i] - dq[i]) for i in range(12)]
    np.testing.assert_allclose(cmd.torque_at(q, dq), expected, rtol=1e-12)
    limit = np.full(12, 2.0)
    np.testing.assert_allclose(cmd.clipped_torque_at(q, dq, limit), np.clip(expected, -2.0, 2.0))


def test_pure_torque_ignores_the_state():
    tau = np.arange(12.0)
    cmd = MotorCommand.pure_torque(tau)
    np.testing.assert_array_equal(cmd.torque_at(np.ones(12), -np.ones(12)), tau)
    tau[0] = 99.0  # the command owns its arrays
    assert cmd.tau_ff[0] == 0.0


def test_reordered_to_the_sdk_order_by_name():
    rng = np.random.default_rng(4)
    cmd = random_command(rng)
    sdk = cmd.reordered(JointMap.unitree_sdk().index)
    for i, name in enumerate(UNITREE_SDK_JOINT_NAMES):
        j = JOINT_NAMES.index(name)
        assert (sdk.q_des[i], sdk.dq_des[i], sdk.kp[i], sdk.kd[i], sdk.tau_ff[i]) == (
            cmd.q_des[j], cmd.dq_des[j], cmd.kp[j], cmd.kd[j], cmd.tau_ff[j])
    back = sdk.reordered(JointMap.unitree_sdk().inverse)
    np.testing.assert_array_equal(back.tau_ff, cmd.tau_ff)


@pytest.mark.parametrize(("field", "value", "message"), [
    ("kp", -1.0, "kp: negative gain at joints [3]"),
    ("kd", -0.5, "kd: negative gain at joints [3]"),
    ("q_des", np.nan, "q_des: non-finite at joints [3]"),
    ("tau_ff", 100.0, "tau_ff: beyond the effort limits at joints [3]"),
])
def test_problems_name_the_field_and_joints(field, value, message):
    cmd = random_command(np.random.default_rng(5))
    getattr(cmd, field)[3] = value
    assert cmd.problems(np.full(12, 23.7)) == message


def test_problems_of_a_good_command_and_a_wrong_shape():
    cmd = random_command(np.random.default_rng(6))
    assert cmd.problems(np.full(12, 23.7)) == ""
    cmd.kd = np.zeros(3)
    assert cmd.problems(np.full(12, 23.7)) == "kd: expected shape (12,), received (3,)"


def slow_problems(cmd: MotorCommand, limit) -> str:
    """``problems`` as NumPy checks it: long doubles hold the same values but are not
    compiled for, so the compiled shortcut for a good command is skipped."""
    fields = ("q_des", "dq_des", "kp", "kd", "tau_ff")
    return MotorCommand(**{f: np.asarray(getattr(cmd, f), dtype=np.longdouble)
                           for f in fields}).problems(limit)


def test_the_compiled_check_of_a_good_command_agrees_with_numpy():
    rng = np.random.default_rng(9)
    limit = np.full(12, 23.7)
    specials = [np.nan, np.inf, -np.inf, -1e-300, -0.0, 23.7, 23.700000000000003, 1e300]
    verdicts = set()
    for _ in range(400):
        cmd = random_command(rng)
        field = ("q_des", "dq_des", "kp", "kd", "tau_ff")[rng.integers(5)]
        getattr(cmd, field)[rng.integers(12)] = specials[rng.integers(len(specials))]
        expected = slow_problems(cmd, limit)
        assert cmd.problems(limit) == expected
        verdicts.add(expected == "")
    assert verdicts == {True, False}
    cmd = random_command(rng)
    assert cmd.problems(np.full(12, np.nan)) == ""  # a NaN limit refuses nothing, as NumPy
    cmd.kp = cmd.kp.astype(np.float32)  # not float64: checked by NumPy
    assert cmd.problems(limit) == ""
    cmd.kp[0] = -1.0
    assert cmd.problems(limit) == "kp: negative gain at joints [0]"
    cmd.kp = np.zeros((12, 1))
    assert cmd.problems(limit) == "kp: expected shape (12,), received (12, 1)"
    cmd.kp = [0.0] * 11 + [-2.0]  # any array-like
    assert cmd.problems(limit) == "kp: negative gain at joints [11]"


@pytest.mark.parametrize(("tau", "expected"), [
    (np.full(12, 23.7), True),
    (np.r_[np.zeros(11), -23.71], False),
    (np.r_[np.zeros(11), np.nan], False),
    (np.zeros(11), False),
    ([0.0] * 12, True),
    (np.zeros(12, dtype=np.float32), True),
    (np.zeros((12, 1)), False),
])
def test_within_effort_limits(tau, expected):
    assert within_effort_limits(tau, np.full(12, 23.7)) is expected


def test_copy_owns_its_arrays():
    cmd = random_command(np.random.default_rng(10))
    copy = cmd.copy()
    copy.kp[0] = -1.0
    assert type(copy) is MotorCommand and cmd.kp[0] >= 0.0
    np.testing.assert_array_equal(copy.tau_ff, cmd.tau_ff)


def test_the_loops_one_call_check_is_the_command_check_and_the_torque_check():
    rng = np.random.default_rng(11)
    limit = np.full(12, 23.7)
    specials = [np.nan, np.inf, -1e-300, 23.7, 23.700000000000003, -30.0]
    verdicts = set()
    for _ in range(300):
        cmd = random_command(rng)
        tau = rng.uniform(-23.7, 23.7, 12)
        if rng.integers(2):
            field = ("q_des", "dq_des", "kp", "kd", "tau_ff")[rng.integers(5)]
            getattr(cmd, field)[rng.integers(12)] = specials[rng.integers(len(specials))]
        if rng.integers(3) == 0:
            tau[rng.integers(12)] = specials[rng.integers(len(specials))]
        expected = cmd.problems(limit) == "" and within_effort_limits(tau, limit)
        assert command_and_torque_fine(cmd.q_des, cmd.dq_des, cmd.kp, cmd.kd, cmd.tau_ff, tau,
                                       limit) is expected
        verdicts.add(expected)
    assert verdicts == {True, False}
    with pytest.raises(TypeError):  # not float64 vectors: the loop falls back to the checks
        command_and_torque_fine(cmd.q_des, cmd.dq_des, cmd.kp, cmd.kd, cmd.tau_ff,
                                tau.astype(np.float32), limit)
