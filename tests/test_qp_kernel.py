"""The compiled assembly builds the same QP terms as the task classes (the reference)."""

import numpy as np
import pinocchio as pin
import pytest

from tasks import ContactTask, PostureTask
from tests.conftest import random_configuration
from wbc import WholeBodyController
from wbc.description import FOOT_RADIUS_M, LEGS
from wbc.qp_kernel import CON, DYN, NV, SUP, TAU, log3


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


def reference_terms(c, q, v):
    """H and f of the tasks, and the contact rows, from the task classes."""
    model, data = c.model, c.model.createData()
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    pin.centerOfMass(model, data, pin.KinematicLevel.ACCELERATION, False)
    H = c._h_const.copy()
    f = np.zeros(H.shape[0])
    contact = ContactTask(model, [f"{leg}_foot" for leg in LEGS], radius_m=FOOT_RADIUS_M,
                          kd=c.config.contact_damping)
    contact.update(model, data, q, v)
    M = np.triu(data.M) + np.triu(data.M, 1).T
    terms = [c.com_task, c.base_task, c.posture_task]
    terms += [c.foot_tasks[leg] for leg in LEGS if leg not in c.stance_legs]
    for task in terms:
        task.update(model, data, q, v)
        weights = task.weight * (task.joint_weights if isinstance(task, PostureTask)
                                 else np.ones(task.dim))
        J = task.jacobian
        H[:NV, :NV] += J.T @ (weights[:, None] * J)
        f[:NV] += J.T @ (weights * (task.drift - task.desired_acceleration))
    f[:30] -= c._rate_weights * c._x_prev
    S = np.hstack([M[6:], -contact.jacobian[:, 6:].T])  # tau = S x + h_a
    H[:30, :30] += c.config.torque_rate_weight * S.T @ S
    f[:30] += c.config.torque_rate_weight * S.T @ (data.nle[6:] - c._tau_prev)
    return H, f, contact, data


@pytest.mark.parametrize("swing", [None, "FR", "RL"])
def test_kernel_matches_task_classes(description, model, swing):
    c = WholeBodyController(base_orientation_ki=0.0)  # the integral is the controller's own
    standing = description.pose("standing")
    c.reset(standing)
    if swing:
        c.set_max_normal_force(swing, 0.0)
        c.set_swing(swing)
        c.set_foot_target(swing, c.foot_position(swing) + [0.05, 0.0, 0.1], [0.1, 0, 0.2], [1, 2, 3])
    c.set_com_target(c.com_target + [0.01, -0.02, 0.0], [0.05, 0.0, 0.0], [0.1, 0.2, 0.0])
    c.set_posture_weights(np.linspace(0.5, 3.0, 12))
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = random_configuration(model, rng, scale=0.1, base=standing)
        v = rng.normal(size=18) * 0.3
        c._update_model(q, v)
        c._assemble(q, v)
        H, f, contact, data = reference_terms(c, q, v)
        p = c.problem
        np.testing.assert_allclose(p.H, H, atol=1e-9)
        np.testing.assert_allclose(p.f, f, atol=1e-9)
        M = np.triu(data.M) + np.triu(data.M, 1).T
        np.testing.assert_allclose(p.A[DYN:DYN + 6, :NV], M[:6], atol=1e-12)
        np.testing.assert_allclose(p.A[TAU:TAU + 12, :NV], M[6:], atol=1e-12)
        np.testing.assert_allclose(p.A[CON:CON + 12, :NV], contact.jacobian, atol=1e-12)
        rhs = contact.kd * contact.error_rate - contact.drift
        for i, leg in enumerate(LEGS):
            rows = slice(CON + 3 * i, CON + 3 * i + 3)
            if leg == swing:
                assert np.all(p.upper[rows] >= 1e30)
            else:
                np.testing.assert_allclose(p.lower[rows], rhs[3 * i:3 * i + 3], atol=1e-9)
        # The support rows: centre of mass inside the (three- or four-foot) polygon.
        com_jac = data.Jcom[:2]
        for k in range(c._n_edges):
            np.testing.assert_allclose(p.A[SUP + k, :NV], c._normals[k] @ com_jac, atol=1e-12)
