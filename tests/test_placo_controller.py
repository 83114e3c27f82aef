"""PlacoController: the BalanceController protocol, standing in MuJoCo, safe failures."""

from __future__ import annotations

import numpy as np
import pytest

from sim.control_loop import ControlLoop
from sim.simulator import Go2Simulator
from wbc.controller.balance_controller import BalanceController
from wbc.controller.control_output import ControlStatus
from wbc.controller.placo_controller import PlacoController
from wbc.core.errors import ConfigurationError, ReachabilityError
from wbc.model.description import LEGS


@pytest.fixture(scope="module")
def controller(description) -> PlacoController:
    return PlacoController(description=description)


@pytest.fixture()
def standing(controller, description):
    sim = Go2Simulator(description=description)
    q, _ = sim.state()
    controller.reset(q)
    return controller, sim


def test_follows_the_balance_controller_protocol(controller):
    assert isinstance(controller, BalanceController)


def test_foot_positions_are_the_feet_in_leg_order(standing):
    controller, _ = standing
    feet = controller.foot_positions()
    for i, leg in enumerate(LEGS):
        np.testing.assert_array_equal(feet[i], controller.foot_position(leg))
    target = controller.foot_position("FR") + [0.05, 0.0, 0.1]
    controller.set_foot_target("FR", target)
    np.testing.assert_array_equal(controller.foot_target("FR"), target)


def test_stands_two_seconds_in_mujoco(controller, description):
    """On the state estimated from the simulated sensors; measured on the truth."""
    loop = ControlLoop.simulated(controller=controller)
    q0, _ = loop.true_state()
    statuses = set()
    for _ in range(2000):
        out = loop.command(*loop.read_state())
        statuses.add(out.status)
        loop.robot.write_command(out)
    q, _ = loop.true_state()
    assert statuses == {ControlStatus.OK}
    assert np.linalg.norm(q[:3] - q0[:3]) < 5e-3
    # The four QP forces carry the robot's weight.
    total = out.forces[:, 2].sum()
    assert total == pytest.approx(description.total_mass * 9.81, rel=0.02)
    assert np.linalg.norm(controller.com_velocity()) < 0.01
    assert set(out.timings) == {"model", "solve", "total"}
    eq, ineq = controller.solution_violations()
    assert eq < 1e-6 and ineq < 1e-6


def test_nan_state_returns_fallback_and_recovers(standing):
    controller, sim = standing
    q, v = sim.state()
    good = controller.step(q, v)
    bad_q = q.copy()
    bad_q[9] = np.nan
    out = controller.step(bad_q, v)
    assert out.status is ControlStatus.FALLBACK
    assert np.isnan(controller.solution_violations()).all()
    assert out.message == "state: non-finite values at q[9]"
    assert np.isfinite(out.tau).all()
    assert np.all(np.abs(out.tau) <= controller.tau_max)
    np.testing.assert_allclose(out.tau, np.clip(good.tau_ff - 2.0 * v[6:], -controller.tau_max,
                                                 controller.tau_max))
    wrong = controller.step(q[:7], v)
    assert wrong.status is ControlStatus.FALLBACK
    assert wrong.message.startswith("state: expected q (19,)")
    assert controller.step(q, v).ok


def test_swing_and_stance_switch_the_contact(standing):
    controller, sim = standing
    q, v = sim.state()
    controller.step(q, v)
    controller.schedule.set_max_normal_force("FR", 0.0)
    assert controller.contacts["FR"].weight_forces == pytest.approx(
        controller.config.weights.force_weight * 1e6)
    controller.schedule.set_swing("FR")
    assert controller.stance_legs == ["FL", "RL", "RR"]
    assert not controller.contacts["FR"].active
    out = controller.step(q, v)
    assert out.ok and np.all(out.forces[1] == 0.0) and "FR_foot" in out.task_errors
    with pytest.raises(ConfigurationError, match="at least three feet must stay in stance"):
        controller.schedule.set_swing("RL")
    with pytest.raises(ConfigurationError, match="FR is in swing"):
        controller.schedule.set_max_normal_force("FR", 10.0)
    far = controller.shoulder_position("FR") + [0.0, 0.0, 0.5]
    with pytest.raises(ReachabilityError, match="reachable: at most 0.40 m"):
        controller.set_foot_target("FR", far)
    controller.set_foot_target("FR", far, clamp_to_reach=True)
    reached = (np.ravel(controller.foot_tasks["FR"].target_world)
               - controller.shoulder_position("FR"))
    np.testing.assert_allclose(reached, [0.0, 0.0, 0.40], atol=1e-12)
    safe = controller.safe_command(v, "guard tripped")
    assert safe.status is ControlStatus.FALLBACK and safe.message == "guard tripped"
    controller.schedule.set_stance("FR", max_normal_force_n=0.0)
    assert controller.contacts["FR"].active and controller.schedule.max_normal_force("FR") == 0.0
    assert controller.support_legs() == ["FL", "RL", "RR"]


def test_posture_and_foot_weights(standing):
    controller, sim = standing
    q, v = sim.state()
    np.testing.assert_allclose(controller.posture_target, q[7:])
    target = q[7:] + 0.05
    controller.set_posture_target(target, velocity=np.full(12, 0.1))
    np.testing.assert_allclose(controller.posture_target, target)
    assert controller.posture_tasks[3].get_joint("FR_hip_joint") == pytest.approx(target[3])
    with pytest.raises(ConfigurationError, match="expected values >= 0"):
        controller.set_posture_weights(np.full(12, -1.0))
    controller.schedule.set_swing("FR")
    controller.set_foot_weight("FR", 0.0)
    out = controller.step(q, v)
    assert out.ok
    with pytest.raises(ConfigurationError, match="FR foot weight"):
        controller.set_foot_weight("FR", -1.0)
    controller.reset(q)
    assert controller.stance_legs == ["FL", "FR", "RL", "RR"]
    np.testing.assert_allclose(controller.posture_target, q[7:])


def test_unknown_and_bad_parameters_are_named_as_the_default_controller_names_them():
    with pytest.raises(ConfigurationError, match=r"^unknown controller parameter\(s\) "
                                                 r"\['com_gain', 'wieght'\]; valid controller "
                                                 r"parameters: solver, gains, "):
        PlacoController(com_gain=1.0, wieght=2.0)
    with pytest.raises(ConfigurationError, match=r"^stance_kp: .*\[0, 500\], received 900"):
        PlacoController(shaping={"stance_kp": 900.0})
