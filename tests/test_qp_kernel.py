"""The QP builder's compiled stages: the reduced QP has the full QP's solution, exactly."""

import numpy as np
import pinocchio as pin
import pytest

from tasks.task_kernels import log3
from tests.conftest import random_configuration
from wbc import WholeBodyController
from wbc.backends.daqp_backend import DaqpBackend
from wbc.controller import qp_kernel
from wbc.model.description import LEGS


@pytest.mark.parametrize("seed", range(4))
def test_log3_matches_pinocchio(seed):
    rng = np.random.default_rng(seed)
    for angle in (0.0, 1e-7, 0.3, 2.0, np.pi - 1e-5, np.pi):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        R = pin.exp3(angle * axis)
        np.testing.assert_allclose(pin.exp3(log3(R)), R, atol=1e-9)
        if angle < np.pi - 1e-3:  # at pi, +axis and -axis are the same rotation
            np.testing.assert_allclose(log3(R), pin.log3(R), atol=1e-9)


def controller_at(model, standing, swing, seed):
    """A controller with ``swing`` legs up, updated at a perturbed state."""
    c = WholeBodyController()
    c.reset(standing)
    for leg in swing:
        c.schedule.set_max_normal_force(leg, 0.0)
        c.schedule.set_swing(leg)
        c.set_foot_target(leg, c.foot_position(leg) + [0.05, 0.0, 0.1], [0.1, 0, 0.2], [1, 2, 3])
    c.set_com_target(c.com_target + [0.01, -0.02, 0.0], [0.05, 0.0, 0.0], [0.1, 0.2, 0.0])
    c.set_posture_weights(np.linspace(0.5, 3.0, 12))
    rng = np.random.default_rng(seed)
    q = random_configuration(model, rng, scale=0.1, base=standing)
    v = rng.normal(size=18) * 0.3
    c.kinematics.compute(q, v)
    c._q = q
    c.balance.before_update()
    c.builder.evaluate()
    return c


@pytest.mark.parametrize("swing", [(), ("FR",), ("RL",)])
@pytest.mark.parametrize("seed", range(3))
def test_reduced_qp_has_the_full_qps_solution(model, standing, swing, seed):
    c = controller_at(model, standing, swing, seed)
    builder = c.builder
    reduced = builder.assemble()
    assert builder.reduced
    layout = builder.layout
    assert layout.n == 18 + 3 * (4 - len(swing)) + 1      # no force variables in the air
    assert reduced.n == 13 and not reduced.is_equality.any()
    z = DaqpBackend().solve(reduced)
    assert z.found, z.reason
    full = builder.assemble_full()   # before accept(): the rate costs pull to the last x
    reference = DaqpBackend().solve(full)
    builder.reduced = True
    x = builder.accept(z.x)[0].copy()
    assert reference.found, reference.reason
    np.testing.assert_allclose(x, reference.x, atol=1e-6, rtol=1e-6)
    eq, ineq = full.violations(x)
    assert eq < 1e-9 and ineq < 1e-7
    # The same cost: the reduced objective equals the full one at the mapped point.
    def objective(p, y):
        return 0.5 * y @ p.H @ y + p.f @ y
    z2 = z.x + 1e-3 * np.random.default_rng(seed).normal(size=z.x.size)
    x2 = builder.plan.reduction.T @ z2 + builder.plan.reduction.t0
    gap = (objective(full, x2) - objective(full, x)) - (objective(reduced, z2)
                                                         - objective(reduced, z.x))
    assert abs(gap) < 1e-9 * max(1.0, abs(objective(full, x)))


@pytest.mark.parametrize("swing", [(), ("RL",)])
def test_any_reduced_point_satisfies_the_eliminated_equalities(model, standing, swing):
    c = controller_at(model, standing, swing, 7)
    builder = c.builder
    builder.assemble()
    entry = builder.plan.reduction
    full = builder.problem
    equality = full.is_equality
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = entry.T @ rng.normal(size=entry.T.shape[1]) * 10.0 + entry.t0
        residual = full.A[equality] @ x - full.lower[equality]
        np.testing.assert_allclose(residual, 0.0, atol=1e-8)


def test_task_costs_match_the_dense_formula(model, standing):
    c = controller_at(model, standing, ("FR",), 3)
    builder = c.builder
    full = builder.assemble_full()
    H = np.zeros_like(full.H)
    f = np.zeros_like(full.f)
    nv = 18
    for task in builder.tasks:
        if task not in builder._active_tasks:
            continue
        w = task.weight * task.row_weights
        residual = task.drift - task.desired_acceleration
        H[:nv, :nv] += task.jacobian.T @ (w[:, None] * task.jacobian)
        f[:nv] += task.jacobian.T @ (w * residual)
    entry = builder.plan
    H += np.diag(entry.weights)
    f -= entry.rate_weights * entry.x_prev
    tau_rows = entry.tau_block.A
    offset = c.kinematics.nonlinear_effects[6:] - builder.tau_prev
    w = c.config.weights.torque_rate_weight
    H += w * tau_rows.T @ tau_rows
    f += w * tau_rows.T @ offset
    np.testing.assert_allclose(full.H, H, atol=1e-9)
    np.testing.assert_allclose(full.f, f, atol=1e-9)
    assert {"FR_foot"} == {t.frame for t in builder._active_tasks if hasattr(t, "frame")}


def test_a_straight_stance_leg_falls_back_to_the_full_qp(model, standing):
    c = WholeBodyController()
    c.reset(standing)
    q = standing.copy()
    q[7 + 3 * LEGS.index("RR") + 1] = 0.0
    q[7 + 3 * LEGS.index("RR") + 2] = 0.0   # knee straight: the leg's Jacobian is singular
    c.kinematics.compute(q, np.zeros(18))
    c.builder.evaluate()
    c.builder.assemble()
    assert not c.builder.reduced
    out = c.step(q, np.zeros(18))
    assert np.isfinite(out.tau).all()


def test_inverse3():
    rng = np.random.default_rng(0)
    L = rng.normal(size=(3, 3))
    out = np.zeros((3, 3))
    assert qp_kernel._inverse3(L, out) == pytest.approx(np.linalg.det(L))
    np.testing.assert_allclose(out, np.linalg.inv(L), atol=1e-12)
    assert qp_kernel._inverse3(np.ones((3, 3)), out) == 0.0


@pytest.fixture
def standing(description):
    return description.pose("standing")
