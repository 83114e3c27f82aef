"""Every task's Jacobian and drift against finite differences, on the configuration manifold.

The tasks are evaluated exactly as the control tick evaluates them: from a
:class:`tasks.RobotKinematics` at the state, by their compiled ``evaluate``.
"""

import numpy as np
import pinocchio as pin
import pytest

from tasks import (
    BaseOrientationTask,
    ComTask,
    ContactForceTask,
    ContactTask,
    FramePositionTask,
    PostureTask,
    RobotKinematics,
    TaskBlock,
)
from tests.conftest import random_configuration
from wbc.core.errors import ConfigurationError, NonFiniteError

H = 1e-6
N_SAMPLES = 10


FRAMES = ("FL_foot", "FR_foot", "RL_foot", "RR_foot", "base")


def updated(model, q, v):
    """Kinematics at (q, v), as the controller computes them each tick."""
    kinematics = RobotKinematics(model, FRAMES)
    kinematics.compute(q, v)
    return kinematics


def bound(task, model):
    task.bind(RobotKinematics(model, FRAMES))
    return task


def samples(model, seed):
    rng = np.random.default_rng(seed)
    for _ in range(N_SAMPLES):
        yield random_configuration(model, rng, scale=0.6), rng.normal(size=model.nv)


def velocity_fd(value, model, q, v):
    """d/dt value(q(t)) at t = 0 along q(t) = q (+) t v, by central differences."""
    plus, minus = pin.integrate(model, q, H * v), pin.integrate(model, q, -H * v)
    return (value(plus) - value(minus)) / (2 * H)


def world_points(model, points):
    """value(qq): the stacked world positions of ``(frame name, point in frame)`` pairs."""
    def value(qq):
        data = model.createData()
        pin.framesForwardKinematics(model, data, qq)
        return np.concatenate([data.oMf[model.getFrameId(n)].act(p) for n, p in points])
    return value


def drift_fd(task, model, q, v):
    """d/dt (J(q(t)) v) along q(t) = q (+) t v with constant v (qdd = 0)."""
    def task_velocity(qq):
        task.evaluate(updated(model, qq, v))
        return task.jacobian @ v
    return velocity_fd(task_velocity, model, q, v)


def check(task, value, model, seed):
    for q, v in samples(model, seed):
        task.evaluate(updated(model, q, v))
        J, drift = task.jacobian.copy(), task.drift.copy()
        np.testing.assert_allclose(J @ v, velocity_fd(value, model, q, v), atol=1e-5, rtol=1e-5)
        np.testing.assert_allclose(drift, drift_fd(task, model, q, v), atol=1e-4, rtol=1e-4)


def test_com_task(model):
    task = ComTask()
    task.set_target(np.zeros(3))
    check(task, lambda qq: pin.centerOfMass(model, model.createData(), qq), model, 0)


@pytest.mark.parametrize("frame,axes", [("FR_foot", "xyz"), ("RL_foot", "xz"), ("base", "z")])
def test_frame_position_task(model, frame, axes):
    task = bound(FramePositionTask(model, frame, axes=axes), model)
    task.set_target(np.zeros(len(axes)))
    rows = ["xyz".index(a) for a in axes]

    def position(qq):
        data = model.createData()
        pin.framesForwardKinematics(model, data, qq)
        return data.oMf[model.getFrameId(frame)].translation[rows]
    check(task, position, model, 1)


def test_base_orientation_task(model):
    task = BaseOrientationTask()
    for q, v in samples(model, 2):
        task.evaluate(updated(model, q, v))
        R = pin.Quaternion(q[3:7]).matrix()
        R_next = pin.Quaternion(pin.integrate(model, q, H * v)[3:7]).matrix()
        np.testing.assert_allclose(task.jacobian @ v, pin.log3(R.T @ R_next) / H, atol=1e-5)
        np.testing.assert_allclose(task.drift, drift_fd(task, model, q, v), atol=1e-6)
        # The error is the rotation from the current to the target orientation, base frame.
        task.set_target(R_next)
        task.evaluate(updated(model, q, v))
        np.testing.assert_allclose(task.error, H * (task.jacobian @ v), atol=1e-9)


def test_posture_task(model):
    task = PostureTask()
    task.set_target(np.zeros(12))
    check(task, lambda qq: qq[7:], model, 3)


@pytest.mark.parametrize("radius", [0.0, 0.022])
def test_contact_task_rolling_point(model, radius):
    frames = ["FL_foot", "FR_foot", "RL_foot", "RR_foot"]
    task = bound(ContactTask(model, frames, radius_m=radius), model)
    for q, v in samples(model, 4):
        task.evaluate(updated(model, q, v))
        data = model.createData()
        pin.framesForwardKinematics(model, data, q)
        # The body point under each sphere centre at this instant.
        points = []
        for name in frames:
            oMf = data.oMf[model.getFrameId(name)]
            points.append((name, oMf.actInv(oMf.translation + np.array([0, 0, -radius]))))
        contact_points = world_points(model, points)
        np.testing.assert_allclose(task.jacobian @ v, velocity_fd(contact_points, model, q, v),
                                   atol=1e-5, rtol=1e-5)
        np.testing.assert_allclose(task.drift, drift_fd(task, model, q, v), atol=1e-4, rtol=1e-4)
        np.testing.assert_allclose(task.error_rate, -(task.jacobian @ v))


def test_desired_acceleration_is_pd_with_critical_damping(model):
    task = ComTask(kp=100.0)
    assert task.kd == pytest.approx(20.0)
    q = random_configuration(model, np.random.default_rng(5))
    v = np.random.default_rng(6).normal(size=18)
    kinematics = updated(model, q, v)
    task.set_target(kinematics.com_position + [0.01, 0.0, 0.0], velocity=[0.1, 0.0, 0.0])
    task.set_feedforward([0.0, 0.0, 1.0])
    task.evaluate(kinematics)
    expected = (100.0 * np.array([0.01, 0, 0])
                + 20.0 * (np.array([0.1, 0, 0]) - kinematics.com_velocity))
    np.testing.assert_allclose(task.desired_acceleration, expected + [0, 0, 1.0], atol=1e-12)


def test_targets_are_copied_and_validated(model):
    task = FramePositionTask(model, "FR_foot")
    target = np.array([0.1, 0.2, 0.3])
    task.set_target(target)
    target[0] = 9.0
    assert task.target[0] == 0.1
    with pytest.raises(NonFiniteError, match="FR_foot.target: non-finite value at index \\[2\\]"):
        task.set_target([0.0, 0.0, np.nan])
    with pytest.raises(ConfigurationError,
                       match=r"expected an array of shape \(3,\), received shape \(2,\)"):
        task.set_target([0.0, 0.0])
    assert task.target[0] == 0.1  # a rejected target leaves the old one


def test_task_without_target_says_so(model):
    task = ComTask()
    kinematics = updated(model, random_configuration(model, np.random.default_rng(0)),
                         np.zeros(18))
    with pytest.raises(ConfigurationError, match="ComTask: target not set; call set_target"):
        task.evaluate(kinematics)


def test_bad_task_parameters(model):
    with pytest.raises(ConfigurationError,
                       match="kp: expected a value in \\[0, inf\\], received -1"):
        ComTask(kp=-1.0)
    with pytest.raises(ConfigurationError, match="unknown frame 'hand'"):
        FramePositionTask(model, "hand")
    with pytest.raises(ConfigurationError, match="axes: expected a subset of 'xyz', received 'xw'"):
        FramePositionTask(model, "FR_foot", axes="xw")
    with pytest.raises(ConfigurationError, match="expected a rotation matrix"):
        BaseOrientationTask().set_target(2.0 * np.eye(3))


def test_a_force_task_s_value_is_the_force_and_its_desired_value_the_target(model):
    """A task on a contact's force variables: ``J f + drift`` is the force itself (closed
    form: the identity over ``force:FR``), its desired value the target."""
    task = ContactForceTask("FR", target_n=[1.0, 2.0, 50.0])
    assert task.variables == ("force:FR",) and task.width(model.nv) == 3
    task.evaluate(updated(model, random_configuration(model, np.random.default_rng(7)),
                        np.zeros(18)))
    forces = np.random.default_rng(8).normal(size=(5, 3))
    np.testing.assert_allclose(forces @ task.jacobian.T + task.drift, forces)
    np.testing.assert_array_equal(task.desired_acceleration, [1.0, 2.0, 50.0])
    with pytest.raises(NonFiniteError, match=r"^FR force\.target: non-finite"):
        task.set_target([0.0, np.nan, 0.0])


def test_a_task_sizes_its_jacobian_when_bound_and_takes_only_a_block_of_that_size(model):
    task = ComTask()
    assert task.jacobian.shape == (3, 0) and task.nv is None   # no robot yet
    task.set_weight(3.0)
    task.bind(RobotKinematics(model, FRAMES))
    assert task.jacobian.shape == (3, model.nv) and task.weight == 3.0
    with pytest.raises(ConfigurationError, match=r"^ComTask: a task block of Jacobian shape "
                                                 r"\(3, 18\) expected, received \(3, 17\)"):
        task.attach(TaskBlock.owned(3, 17))
    with pytest.raises(ConfigurationError, match=r"^ComTask\.jacobian: cannot be replaced"):
        task.jacobian = np.zeros((3, model.nv))
    with pytest.raises(ConfigurationError, match=r"^variables: unknown variable 'torque'"):
        type("Odd", (ComTask,), {"variables": ("torque",)})().bind(RobotKinematics(model, FRAMES))
