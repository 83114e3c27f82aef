"""The problem builder: tasks handed their blocks, costs on any variable, the elimination the
constraints declare, one tick plan per layout."""

import numpy as np
import pytest

from tasks import (
    ContactForceTask,
    Elimination,
    FloatingBaseDynamics,
    StanceContacts,
    Task,
    TaskBlock,
    force_variable,
)
from tasks.constraint import Constraint
from tests.conftest import random_configuration
from wbc import WholeBodyController
from wbc.backends.daqp_backend import DaqpBackend
from wbc.controller.tick_plan import TickPlan
from wbc.core.errors import ConfigurationError


@pytest.fixture(scope="module")
def standing(description):
    return description.pose("standing")


def states(model, standing, n, seed, speed=0.2):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        yield (random_configuration(model, rng, scale=0.05, base=standing),
               speed * rng.normal(size=18))


# ---------------------------------------------------------------------------- task blocks


class _ReplacingTask(Task):
    """A base-height task that assigns its Jacobian instead of writing into it."""

    dim = 1
    frames = ("base",)

    def __init__(self):
        super().__init__(kp=10.0)
        self._has_target = True

    def compute(self, kinematics):
        i = self.frame_indices[0]
        self.jacobian = kinematics.frame_jacobian[i, 2:3].copy()   # the mistake
        self.drift[0] = kinematics.frame_drift[i, 2]


def test_a_task_that_replaces_its_jacobian_raises_naming_it(standing):
    controller = WholeBodyController()
    controller.add_task(_ReplacingTask())
    controller.reset(standing)
    with pytest.raises(ConfigurationError) as err:
        controller.step(standing, np.zeros(18))
    assert str(err.value) == (
        "_ReplacingTask.jacobian: cannot be replaced (a view of the QP's task block: the QP "
        "reads it where it is, so a new array would leave the QP unchanged); write into it "
        "instead: jacobian[...] = values")


def test_replacing_row_weights_raises_and_writing_into_them_reaches_the_qp(standing):
    controller = WholeBodyController()
    controller.reset(standing)
    with pytest.raises(ConfigurationError, match=r"^ComTask\.row_weights: cannot be replaced .*"
                                                 r"write into it instead: row_weights\[\.\.\.\]"):
        controller.com_task.row_weights = np.array([1.0, 1.0, 0.0])
    with pytest.raises(ConfigurationError, match=r"^BaseOrientationTask\.bias: cannot be"):
        controller.base_task.bias = np.zeros(3)
    for name in ("gains", "drift", "desired_acceleration", "error", "reference"):
        with pytest.raises(ConfigurationError, match=rf"^ComTask\.{name}: cannot be replaced"):
            setattr(controller.com_task, name, np.zeros(3))
    controller.step(standing, np.zeros(18))
    before = controller.builder.assemble_full().H.copy()
    controller.com_task.row_weights[2] = 0.0          # in place: the QP's own array
    controller.builder.evaluate()
    after = controller.builder.assemble_full().H
    J = controller.com_task.jacobian[2]
    w = controller.com_task.weight
    np.testing.assert_allclose(before[:18, :18] - after[:18, :18], w * np.outer(J, J),
                               atol=1e-9)


def test_registered_tasks_write_into_the_stacked_rows_and_keep_their_values_when_removed():
    controller = WholeBodyController()
    task = ContactForceTask("FR", weight=0.5, target_n=[0.0, 0.0, 60.0])
    task.set_row_weights([0.0, 0.0, 2.0])
    controller.add_task(task)
    stack = controller.builder._stack
    assert np.shares_memory(task.jacobian, stack.jacobian)
    assert np.shares_memory(task.row_weights, stack.row_weights)
    assert np.shares_memory(task.gains, stack.gains)
    np.testing.assert_array_equal(task.jacobian, np.eye(3))   # its constant entries moved in
    np.testing.assert_array_equal(task.row_weights, [0.0, 0.0, 2.0])
    assert task.weight == 0.5
    assert isinstance(task.block, TaskBlock)
    controller.remove_task(task)
    assert not np.shares_memory(task.jacobian, controller.builder._stack.jacobian)
    np.testing.assert_array_equal(task.row_weights, [0.0, 0.0, 2.0])
    np.testing.assert_array_equal(task.jacobian, np.eye(3))


# ---------------------------------------------------------------------------- costs on forces


def _with_and_without(task, standing, swing=()):
    """The same controller state with and without ``task``: (builder without, with)."""
    out = []
    for add in (False, True):
        controller = WholeBodyController()
        if add:
            controller.add_task(task)
        controller.reset(standing)
        for leg in swing:
            controller.schedule.set_max_normal_force(leg, 0.0)
            controller.schedule.set_swing(leg)
        q = standing.copy()
        q[0] += 0.003
        controller.kinematics.compute(q, 0.1 * np.ones(18))
        controller.builder.evaluate()
        out.append(controller.builder)
    return out


@pytest.mark.parametrize("reduced", [False, True])
def test_a_force_task_adds_its_closed_form_cost(standing, reduced):
    target = np.array([1.0, -2.0, 60.0])
    weight = 0.25
    task = ContactForceTask("FR", weight=weight, target_n=target)
    task.set_row_weights([1.0, 2.0, 3.0])
    without, with_task = _with_and_without(task, standing)
    columns = with_task.layout.force_slice("FR")
    assert with_task.layout.columns(task.variables).tolist() == list(range(columns.start,
                                                                           columns.stop))
    W = weight * np.diag([1.0, 2.0, 3.0])
    if reduced:
        a, b = without.assemble(), with_task.assemble()
        assert without.reduced and with_task.reduced
        T, t0 = with_task.plan.reduction.T[columns], with_task.plan.reduction.t0[columns]
        np.testing.assert_allclose(b.H - a.H, T.T @ W @ T, atol=1e-9)
        np.testing.assert_allclose(b.f - a.f, T.T @ W @ (t0 - target), atol=1e-9)
    else:
        a, b = without.assemble_full(), with_task.assemble_full()
        dH, df = np.zeros_like(a.H), np.zeros_like(a.f)
        dH[columns, columns] = W
        df[columns] = -W @ target
        np.testing.assert_allclose(b.H - a.H, dH, atol=1e-12)
        np.testing.assert_allclose(b.f - a.f, df, atol=1e-12)
    # The task's value is the force itself: J x_FR + drift at any x.
    x = np.random.default_rng(0).normal(size=with_task.layout.n)
    np.testing.assert_allclose(task.jacobian @ x[columns] + task.drift, x[columns])


def test_a_force_task_on_a_foot_in_the_air_changes_nothing(standing):
    task = ContactForceTask("FR", weight=1.0, target_n=[0.0, 0.0, 60.0])
    without, with_task = _with_and_without(task, standing, swing=("FR",))
    assert with_task.layout.columns(task.variables).tolist() == [-1, -1, -1]
    a, b = without.assemble(), with_task.assemble()
    np.testing.assert_array_equal(a.H, b.H)
    np.testing.assert_array_equal(a.f, b.f)


@pytest.mark.parametrize("eliminate", [True, False])
def test_a_force_task_moves_the_load_onto_its_foot(standing, eliminate):
    free = WholeBodyController(solver={"eliminate_dynamics": eliminate})
    pulled = WholeBodyController(solver={"eliminate_dynamics": eliminate})
    task = pulled.add_task(ContactForceTask("FR", weight=1.0, target_n=[0.0, 0.0, 60.0]))
    task.set_row_weights([0.0, 0.0, 1.0])   # the normal force only
    for c in (free, pulled):
        c.reset(standing)
    for _ in range(50):
        a, b = free.step(standing, np.zeros(18)), pulled.step(standing, np.zeros(18))
        assert a.ok and b.ok and pulled.builder.reduced is eliminate
    assert a.forces[1, 2] < 45.0                      # a front foot's share of the weight
    assert abs(b.forces[1, 2] - 60.0) < 0.5           # pulled to 60 N
    assert b.forces[:, 2].sum() == pytest.approx(a.forces[:, 2].sum(), rel=0.02)


def test_force_variables_of_an_unknown_contact_are_refused():
    controller = WholeBodyController()
    with pytest.raises(ConfigurationError, match=r"^ContactForceTask\.variables: unknown contact "
                                                 r"in 'force:XX'; valid: \['force:FL', "):
        controller.add_task(ContactForceTask("XX"))
    assert force_variable("FR") == "force:FR"


# ---------------------------------------------------------------------------- elimination


class _FloatingBaseRows(FloatingBaseDynamics):
    """The same rows, not declared eliminable: the builder must keep them."""

    eliminable_as = None


class _StanceRows(Constraint):
    """Stance contacts written by a user, as a plain constraint (no declaration)."""

    name = "stance contacts"
    equality = True

    def __init__(self, contacts):
        self.contacts = contacts

    def rows(self, layout):
        return 3 * len(layout.force_contacts)

    def write(self, kinematics, layout, block):
        rows = [3 * i + a for i in layout.loaded for a in range(3)]
        task = self.contacts
        block.A[:, :layout.nv] = task.jacobian[rows]
        rhs = task.desired_acceleration[rows] - task.drift[rows]
        block.lower[:], block.upper[:] = rhs, rhs


def _replacing(kind, builtin_type):
    controller = WholeBodyController()
    old = next(c for c in controller.constraints if type(c) is builtin_type)
    controller.remove_constraint(old)
    controller.add_constraint(kind(controller.contact_task))
    return controller


@pytest.mark.parametrize("kind, builtin_type", [(_FloatingBaseRows, FloatingBaseDynamics),
                                                (_StanceRows, StanceContacts)])
def test_a_constraint_that_does_not_allow_elimination_gives_the_full_qp_and_the_same_answer(
        kind, builtin_type, model, standing):
    reduced, full = WholeBodyController(), _replacing(kind, builtin_type)
    assert reduced.builder.can_reduce and not full.builder.can_reduce
    for c in (reduced, full):
        c.reset(standing)
    assert full.builder.reduced_problem is None
    for leg_up, (q, v) in zip([None, None, "RL", "RL"], states(model, standing, 4, seed=5)):
        if leg_up and leg_up in reduced.schedule.stance_legs:
            for c in (reduced, full):
                c.schedule.set_max_normal_force(leg_up, 0.0)
                c.schedule.set_swing(leg_up)
        a, b = reduced.step(q, v), full.step(q, v)
        assert a.ok and b.ok, b.message
        assert reduced.builder.reduced and not full.builder.reduced
        np.testing.assert_allclose(b.tau_ff, a.tau_ff, atol=1e-6)
        np.testing.assert_allclose(b.forces, a.forces, atol=1e-6)
        eq, ineq = full.problem.violations(full.last_solution)
        assert eq < 1e-8 and ineq < 1e-8


def test_elimination_is_what_the_constraints_declare():
    controller = WholeBodyController()
    kinds = {c.eliminable_as for c in controller.constraints}
    assert kinds == {Elimination.FLOATING_BASE_DYNAMICS, Elimination.STANCE_CONTACTS, None}
    dynamics = next(c for c in controller.constraints
                    if c.eliminable_as is Elimination.FLOATING_BASE_DYNAMICS)
    controller.remove_constraint(dynamics)
    assert not controller.builder.can_reduce       # one kind alone cannot be eliminated
    controller.add_constraint(dynamics)
    assert controller.builder.can_reduce
    controller.add_constraint(FloatingBaseDynamics(controller.contact_task))
    assert not controller.builder.can_reduce       # twice: which one would it be?


def test_without_torque_limits_the_torques_still_come_from_the_solution(model, standing):
    reference, bare = WholeBodyController(), WholeBodyController()
    bare.remove_constraint(next(c for c in bare.constraints if c.gives_torques))
    for c in (reference, bare):
        c.reset(standing)
    for q, v in states(model, standing, 3, seed=9, speed=0.02):
        a, b = reference.step(q, v), bare.step(q, v)
        assert b.ok and bare.builder.reduced
        assert np.all(np.abs(a.tau_ff) < reference.tau_max - 1.0)    # the limits do not bind
        np.testing.assert_allclose(b.tau_ff, a.tau_ff, atol=1e-6)
        assert "joint torques" in bare.problem.row_groups


# ---------------------------------------------------------------------------- tick plans


def test_one_plan_per_layout_made_once_and_dropped_when_registration_changes(standing):
    controller = WholeBodyController()
    controller.reset(standing)
    plans = controller.builder._plans
    assert set(plans) == {("FL", "FR", "RL", "RR"), ("FR", "RL", "RR"), ("FL", "RL", "RR"),
                          ("FL", "FR", "RR"), ("FL", "FR", "RL"),
                          ("FL", "RR"), ("FR", "RL")}  # the trot's diagonal pairs
    assert all(isinstance(p, TickPlan) and p.reduction is not None for p in plans.values())
    four = plans[("FL", "FR", "RL", "RR")]
    controller.schedule.set_max_normal_force("FR", 0.0)
    controller.schedule.set_swing("FR")
    assert controller.step(standing, np.zeros(18)).ok
    controller.schedule.set_stance("FR", max_normal_force_n=100.0)
    assert controller.step(standing, np.zeros(18)).ok
    assert controller.builder.plan is four and len(plans) == 7   # kept, not remade
    controller.add_task(ContactForceTask("FR"))
    assert len(plans) == 0                                       # the stack changed
    assert controller.step(standing, np.zeros(18)).ok
    assert len(plans) == 1 and controller.builder.plan is not four


def test_a_plan_s_calls_are_bound_to_its_arrays(standing):
    controller = WholeBodyController()
    controller.reset(standing)
    plan = controller.builder.plan
    assert len(plan.calls) == len(controller.constraints) - 2   # the eliminated two are not
    assert len(plan.eliminated_calls) == 2                      # run unless asked for
    problem = controller.builder.assemble()
    result = DaqpBackend().solve(problem)
    assert result.found and problem is plan.reduced
