"""The QP controller: constraint satisfaction, physics consistency, failures, bad input."""

import math
from dataclasses import fields, replace

import numpy as np
import pinocchio as pin
import pytest

from tasks import ContactTask, RobotKinematics
from tests.conftest import random_configuration
from wbc import ControllerConfig, WholeBodyController
from wbc.backends import available_backends
from wbc.controller.control_output import ControlStatus
from wbc.controller.controller_config import PARTS
from wbc.core.errors import ConfigurationError, NonFiniteError, ReachabilityError, UnknownNameError
from wbc.model.description import FOOT_RADIUS_M, LEGS


@pytest.fixture(scope="module")
def standing(description):
    return description.pose("standing")


@pytest.fixture()
def controller(standing):
    c = WholeBodyController()
    c.reset(standing)
    return c


def perturbed_states(model, standing, n, seed):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield random_configuration(model, rng, scale=0.05, base=standing), 0.2 * rng.normal(size=18)


def check_solution(c, q, v, out, swing=()):
    """Dynamics, contacts, friction, force bounds and torque limits, independently checked."""
    model, data = c.model, c.model.createData()
    qdd, forces = out.qdd, out.forces
    # The reference contact model: the task class, checked against finite differences,
    # on kinematics of its own.
    feet = [f"{leg}_foot" for leg in LEGS]
    contact = ContactTask(model, feet, radius_m=FOOT_RADIUS_M)
    kinematics = RobotKinematics(model, feet)
    kinematics.compute(q, v)
    contact.bind(kinematics)
    contact.evaluate(kinematics)
    contact_jac = contact.jacobian
    # Full inverse dynamics: M qdd + h - J^T f = [0 (base); tau (joints)].
    generalized = pin.rnea(model, data, q, v, qdd) - contact_jac.T @ forces.reshape(-1)
    np.testing.assert_allclose(generalized[:6], 0.0, atol=1e-6)
    np.testing.assert_allclose(generalized[6:], out.tau_ff, atol=1e-6)  # no friction model
    mu = c.config.contacts.friction_coefficient
    for i, leg in enumerate(LEGS):
        f = forces[i]
        if leg in swing:
            np.testing.assert_allclose(f, 0.0, atol=1e-9)
            continue
        rows = slice(3 * i, 3 * i + 3)
        acc = contact_jac[rows] @ qdd + contact.drift[rows]
        np.testing.assert_allclose(acc, -c.config.gains.contact_damping * contact_jac[rows] @ v,
                                   atol=1e-6)
        assert abs(f[0]) <= mu * f[2] + 1e-7 and abs(f[1]) <= mu * f[2] + 1e-7
        low = c.config.contacts.min_normal_force_n
        assert low - 1e-7 <= f[2] <= c.schedule.max_normal_force(leg) + 1e-7
    assert np.all(np.abs(out.tau_ff) <= c.tau_max + 1e-6)


def test_one_line_construction_and_defaults():
    c = WholeBodyController()
    assert c.config.solver.backend == "daqp"
    assert c.config.limits.torque_limit_fraction == 0.9
    np.testing.assert_allclose(c.tau_max, 0.9 * c.description.effort_limit)


def test_standing_solution_satisfies_every_constraint(controller, model, standing):
    for q, v in perturbed_states(model, standing, 10, seed=0):
        out = controller.step(q, v)
        assert out.status is ControlStatus.OK, out.message
        check_solution(controller, q, v, out)
        eq, ineq = controller.problem.violations(controller.last_solution)
        assert eq < 1e-7 and ineq < 1e-7
        assert set(out.timings) == {"model", "assembly", "solve", "total"}


def test_three_leg_solution_has_zero_swing_force(controller, model, standing):
    controller.schedule.set_max_normal_force("FR", 0.0)
    controller.schedule.set_swing("FR")
    assert controller.stance_legs == ["FL", "RL", "RR"]
    for q, v in perturbed_states(model, standing, 5, seed=1):
        out = controller.step(q, v)
        assert out.ok, out.message
        check_solution(controller, q, v, out, swing=("FR",))
        assert "FR_foot" in out.task_errors


def test_weight_is_carried_by_the_feet(controller, standing, description):
    out = controller.step(standing, np.zeros(18))
    assert out.forces[:, 2].sum() == pytest.approx(description.total_mass * 9.81, rel=0.02)


def test_non_finite_state_falls_back_and_recovers(controller, standing):
    good = controller.step(standing, np.zeros(18))
    v = np.zeros(18)
    v[7] = np.nan
    out = controller.step(standing, v)
    assert out.status is ControlStatus.FALLBACK
    assert out.message == "state: non-finite values at v[7]"
    assert np.all(np.isfinite(out.tau)) and np.all(np.abs(out.tau) <= controller.tau_max)
    np.testing.assert_allclose(out.tau, good.tau_ff, atol=1e-9)  # damping of finite v only
    assert (out.kp == 0).all() and (out.kd == controller.config.shaping.fallback_damping).all()
    assert controller.step(standing, np.zeros(18)).ok


def test_wrong_state_shape_falls_back(controller, standing):
    out = controller.step(standing[:18], np.zeros(18))
    assert out.status is ControlStatus.FALLBACK
    assert "expected q (19,) and v (18,), received (18,) and (18,)" in out.message


def test_infeasible_qp_names_the_group_and_commands_the_relaxed_solution(standing):
    c = WholeBodyController(limits={"torque_limit_fraction": 0.01})
    c.reset(standing)
    out = c.step(standing, np.zeros(18))
    assert out.status is ControlStatus.RELAXED
    assert out.infeasible_group == "torque limits"
    assert out.message == ("QP failed: DAQP: infeasible; infeasible constraint group: torque "
                           "limits; commanded the solution with that group relaxed")
    assert np.all(np.abs(out.tau) <= c.tau_max + 1e-12)
    assert c.failures == 1
    assert c.step(standing, np.zeros(18)).status is ControlStatus.RELAXED  # still consistent


def test_diagnose_names_nothing_on_a_feasible_qp_and_the_culprit_on_an_infeasible_one(
        controller, standing):
    assert controller.step(standing, np.zeros(18)).ok
    assert controller.diagnose() == ("", None)  # it used to name "torque limits" here
    controller.schedule.set_max_normal_force("FR", 0.0)
    controller.schedule.set_swing("FR")
    assert controller.step(standing, np.zeros(18)).ok
    assert controller.diagnose() == ("", None)
    # Torque limits of 0.1 % of the URDF's: standing on three feet is impossible.
    controller.tau_max = 1e-3 * controller.tau_max
    out = controller.step(standing, np.zeros(18))  # the new limits reach the QP
    assert out.status is ControlStatus.RELAXED and out.infeasible_group == "torque limits"
    group, relaxed = controller.diagnose()
    assert group == "torque limits"
    assert relaxed is not None and relaxed.found


def test_fallback_damps_joint_velocity(controller, standing):
    controller.step(standing, np.zeros(18))
    good = controller.recovery.tau_good.copy()
    v = np.zeros(18)
    v[6:] = 1.0
    q = standing.copy()
    q[0] = np.inf
    out = controller.step(q, v)
    np.testing.assert_allclose(out.tau, np.clip(good - controller.config.shaping.fallback_damping,
                                                 -controller.tau_max, controller.tau_max))


def test_unreachable_foot_target_raises_and_keeps_old_target(controller, standing):
    controller.step(standing, np.zeros(18))
    old = controller.foot_tasks["FR"].target.copy()
    with pytest.raises(ReachabilityError, match="reachable: at most 0.40 m"):
        controller.set_foot_target("FR", [1.0, -0.15, 0.4])
    np.testing.assert_array_equal(controller.foot_tasks["FR"].target, old)
    with pytest.raises(NonFiniteError):
        controller.set_com_target([0.0, np.nan, 0.3])


def test_references_are_set_all_or_nothing(controller, standing):
    """A trajectory's target, velocity and feed-forward are stored together (float64 vectors
    by the compiled path, anything else converted); a bad one leaves all three unchanged."""
    controller.step(standing, np.zeros(18))
    foot = controller.foot_position("FR") + [0.0, 0.0, 0.05]
    controller.set_foot_target("FR", foot, np.array([0.0, 0.0, 0.1]), np.array([0.0, 0.0, 1.0]))
    task = controller.foot_tasks["FR"]
    np.testing.assert_array_equal(task.reference, [foot, [0.0, 0.0, 0.1], [0.0, 0.0, 1.0]])
    foot[2] += 0.01  # the caller's array is not held
    assert controller.foot_target("FR")[2] == pytest.approx(foot[2] - 0.01)
    before = task.reference.copy()
    for bad, match in ((([0.1, 0.0, np.inf]), "FR_foot.target_velocity: non-finite"),
                       ((0.0, 0.0), "FR_foot.target_velocity: expected an array of shape")):
        with pytest.raises(ConfigurationError, match=match):
            controller.set_foot_target("FR", foot, np.array(bad), None)
    with pytest.raises(NonFiniteError, match="FR_foot.feedforward: non-finite"):
        controller.set_foot_target("FR", foot, None, np.array([np.nan, 0.0, 0.0]))
    np.testing.assert_array_equal(task.reference, before)
    controller.set_com_target([0.0, 0.01, 0.3], [0, 0, 0], [0, 0, 0])  # lists: converted
    np.testing.assert_array_equal(controller.com_target, [0.0, 0.01, 0.3])
    with pytest.raises(ConfigurationError, match="ComTask.feedforward: expected an array"):
        controller.set_com_target(np.zeros(3), np.zeros(3), np.zeros(2))
    np.testing.assert_array_equal(controller.com_target, [0.0, 0.01, 0.3])


def test_foot_positions_are_the_feet_in_leg_order(controller, standing):
    controller.step(standing, np.zeros(18))
    feet = controller.foot_positions()
    for i, leg in enumerate(LEGS):
        np.testing.assert_array_equal(feet[i], controller.foot_position(leg))
    with pytest.raises(ValueError):
        feet[0, 0] = 1.0  # a read-only view of the controller's kinematics


def test_bad_parameters_are_named():
    with pytest.raises(ConfigurationError, match=r"^unknown controller parameter\(s\) "
                                                 r"\['friction', 'kp'\]; valid controller "
                                                 r"parameters: solver, gains, weights, "
                                                 r"contacts, limits, shaping$"):
        WholeBodyController(friction="high", kp=1.0)
    with pytest.raises(UnknownNameError, match=r"^unknown controller parameter 'friction'; "
                                               r"valid controller parameters: solver, gains, "
                                               r"weights, contacts, limits, shaping$"):
        ControllerConfig(friction="high")  # not Python's bare TypeError
    with pytest.raises(UnknownNameError, match=r"^unknown controller parameter 'kp'"):
        replace(ControllerConfig(), kp=1.0)
    with pytest.raises(ConfigurationError,
                       match="friction_coefficient: expected a value in \\(0, 5\\], received 0"):
        ControllerConfig(contacts={"friction_coefficient": 0.0})
    with pytest.raises(ConfigurationError,
                       match="min_normal_force_n: expected less than max_normal_force_n"):
        ControllerConfig(contacts={"min_normal_force_n": 300.0})
    with pytest.raises(UnknownNameError,
                       match="unknown backend 'gurobi'; installed backends: daqp"):
        WholeBodyController(solver={"backend": "gurobi"})


def every_bad_value(config: ControllerConfig):
    """``(part, field, value, label, range text)``: one value below and one above each
    numeric field's range, a NaN and a string, for every numeric field of every part."""
    for part_name, part in PARTS:
        yield from _bad_values(part_name, part)


def _bad_values(part_name, part):
    for f in fields(part):
        if f.name in ("backend", "eliminate_dynamics"):
            continue
        low, high, inclusive = part.RANGES.get(f.name, (0.0, None, True))
        interval = f"{'[' if inclusive else '('}{low:g}, {'inf' if high is None else f'{high:g}'}]"
        bad = [low - 1.0 if inclusive else low, math.nan, "high"]
        if high is not None:
            bad.append(high * 2.0)
        for value in bad:
            if f.name in part.PER_JOINT_TYPE:
                yield part_name, f.name, (0.0, 0.0, value), f"{f.name} (calf)", interval
            else:
                yield part_name, f.name, value, f.name, interval


def test_every_bad_value_names_the_field_and_its_range():
    checked = 0
    for part, name, value, label, interval in every_bad_value(ControllerConfig()):
        with pytest.raises(ConfigurationError) as err:
            ControllerConfig(**{part: {name: value}})
        assert str(err.value).startswith(f"{label}: expected a "), (name, value)
        assert f" {interval}, received " in str(err.value), (name, value, str(err.value))
        checked += 1
    assert checked > 100
    # A stance gain below its range used to report [0, inf], the range of the first check.
    with pytest.raises(ConfigurationError, match=r"^stance_kp: expected a value in \[0, 500\], "
                                                 r"received -1$"):
        ControllerConfig(shaping={"stance_kp": -1.0})
    with pytest.raises(NonFiniteError, match=r"^com_kp: expected a finite number in \[0, inf\], "
                                             r"received nan$"):
        ControllerConfig(gains={"com_kp": math.nan})
    with pytest.raises(ConfigurationError, match=r"^backend: expected a backend name such as "
                                                 r"'daqp' \(wbc.backends.available_backends\(\)"):
        ControllerConfig(solver={"backend": 3})
    with pytest.raises(ConfigurationError, match=r"^eliminate_dynamics: expected True or False"):
        ControllerConfig(solver={"eliminate_dynamics": 1})


def test_contact_changes_are_validated(controller):
    controller.schedule.set_max_normal_force("FR", 0.0)
    controller.schedule.set_swing("FR")
    with pytest.raises(ConfigurationError, match="at least three feet must stay in stance"):
        controller.schedule.set_swing("FL")
    with pytest.raises(ConfigurationError, match="FR is in swing; call set_stance"):
        controller.schedule.set_max_normal_force("FR", 10.0)
    with pytest.raises(ConfigurationError, match="FL max_normal_force_n: expected a value "
                                                 "in \\[0, 250\\], received 300"):
        controller.schedule.set_max_normal_force("FL", 300.0)
    with pytest.raises(UnknownNameError,
                       match="unknown leg 'XX'; valid legs: FL, FR, RL, RR"):
        controller.schedule.set_swing("XX")
    controller.schedule.set_stance("FR")
    assert controller.stance_legs == list(LEGS)


@pytest.mark.parametrize("backend", [b for b in available_backends() if b != "daqp"])
def test_backends_agree_with_daqp(backend, standing, model):
    reference = WholeBodyController()
    other = WholeBodyController(solver={"backend": backend})
    reference.reset(standing)
    other.reset(standing)
    for q, v in perturbed_states(model, standing, 3, seed=2):
        a, b = reference.step(q, v), other.step(q, v)
        assert a.ok and b.ok, b.message
        # OSQP (first order, polished) lands within 10 mN m of DAQP on the reduced QP.
        atol = 1e-2 if "osqp" in backend else 1e-3
        np.testing.assert_allclose(b.tau_ff, a.tau_ff, atol=atol)
        eq, ineq = other.problem.violations(other.last_solution)
        assert eq < 1e-5 and ineq < 1e-5


def _lift_in_lockstep(controllers, model, standing):
    """Step the controllers through the same states, FR unloaded and raised halfway."""
    outputs = [[] for _ in controllers]
    for i, (q, v) in enumerate(perturbed_states(model, standing, 12, seed=11)):
        for c, out in zip(controllers, outputs):
            if i == 6:
                c.schedule.set_max_normal_force("FR", 0.0)
                c.schedule.set_swing("FR")
            out.append(c.step(q, v))
    return outputs


def test_reset_prepares_the_raised_foot_layouts_without_changing_any_tick(model, standing):
    prepared = WholeBodyController()
    prepared.reset(standing)
    lazy = WholeBodyController()
    lazy.prepared_supports = ()
    lazy.reset(standing)
    # Four feet, each three-foot set, the trot's two diagonal pairs.
    assert len(prepared.builder._plans) == 7 and len(lazy.builder._plans) == 1
    assert prepared.builder.layout.loaded.tolist() == [0, 1, 2, 3]  # still on four feet
    for a, b in zip(*_lift_in_lockstep([prepared, lazy], model, standing)):
        assert a.ok and b.ok
        for field in ("tau", "q_des", "dq_des", "tau_ff", "qdd", "forces"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert len(prepared.builder._plans) == 7  # the raise used a prepared layout


def test_the_command_shaped_inside_the_compiled_solve_is_the_python_paths(model, standing):
    compiled = WholeBodyController()
    compiled.reset(standing)
    python = WholeBodyController()
    python.reset(standing)
    python.builder.solve = lambda backend: None  # solve, accept and shape in Python
    for a, b in zip(*_lift_in_lockstep([compiled, python], model, standing)):
        assert a.ok and b.ok
        for field in ("q_des", "dq_des", "kp", "kd", "tau_ff", "tau", "qdd", "forces"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)
        assert a.task_errors == b.task_errors and list(a.task_errors) == list(b.task_errors)
    assert "FR_foot" in a.task_errors and a.kp[3] == compiled.config.shaping.swing_kp
    assert not np.shares_memory(a.tau, compiled.motor.command_rows)


def test_torque_limits_changed_after_reset_reach_every_prepared_layout(standing, model):
    c = WholeBodyController()
    c.reset(standing)
    limits = c.tau_max
    limits[:] = 0.0  # a copy: the controller's limits are unchanged
    np.testing.assert_allclose(c.tau_max, 0.9 * c.description.effort_limit)
    c.tau_max = 0.5 * c.description.effort_limit
    _lift_in_lockstep([c], model, standing)  # ends on three feet, in a prepared layout
    problem, h = c.builder.problem, c.kinematics.nonlinear_effects[6:]
    rows = [i for i, group in enumerate(problem.row_groups) if group == "torque limits"]
    np.testing.assert_allclose(problem.upper[rows] + h, 0.5 * c.description.effort_limit)
    np.testing.assert_allclose(problem.lower[rows] + h, -0.5 * c.description.effort_limit)


def test_read_only_and_strided_states_are_taken(controller, standing):
    q, v = standing.copy(), np.zeros(18)
    q.flags.writeable = v.flags.writeable = False
    assert controller.step(q, v).ok
    strided = np.zeros((19, 2))
    strided[:, 0] = standing
    assert controller.step(strided[:, 0], np.zeros((18, 3))[:, 1]).ok


def test_torque_limits_changed_after_reset_also_bound_the_feed_forward(standing):
    c = WholeBodyController(shaping={"known_joint_friction": (5.0, 5.0, 5.0)})  # pushes tau_ff up
    c.reset(standing)
    c.tau_max = np.full(12, 4.0)
    v = np.zeros(18)
    v[6:] = 2.0  # moving joints: the friction term is about 5 N m on each
    out = c.step(standing, v)
    assert np.all(np.abs(out.tau_ff) <= 4.0 + 1e-12)
    np.testing.assert_array_equal(c.motor.tau_max, np.full(12, 4.0))
