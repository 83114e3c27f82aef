"""After a failed solve: a fresh workspace of the configured backend; DAQP names the culprit."""

import numpy as np
import pytest

from tests.failing_backends import failing
from wbc import WholeBodyController
from wbc.backends import available_backends, register_backend
from wbc.backends.backend import unregister_backend
from wbc.backends.daqp_backend import DaqpBackend
from wbc.controller.control_output import ControlStatus

pytestmark = pytest.mark.skipif("osqp" not in available_backends(),
                                reason="OSQP is not installed here")


def _failing_osqp():
    from wbc.backends.osqp_backend import OsqpBackend

    return failing(OsqpBackend, "failing_osqp")


@pytest.fixture
def failing_osqp():
    register_backend("failing_osqp", _failing_osqp())
    yield "failing_osqp"
    unregister_backend("failing_osqp")


def test_a_solver_failure_is_solved_again_by_a_fresh_workspace_of_the_same_backend(
        failing_osqp, description, monkeypatch):
    controller = WholeBodyController(solver={"backend": failing_osqp})
    q = description.pose("standing")
    controller.reset(q)
    assert controller.step(q, np.zeros(18)).ok
    daqp_solves = []
    solve = DaqpBackend.solve
    monkeypatch.setattr(DaqpBackend, "solve",
                        lambda self, problem: daqp_solves.append(1) or solve(self, problem))
    controller.backend.fail_ticks = 1
    out = controller.step(q, np.zeros(18))
    assert out.status is ControlStatus.RESOLVED
    assert out.message == ("QP failed: injected failure; the problem is feasible: commanded "
                           "a fresh OSQP solution")
    assert daqp_solves == []            # no DAQP in between: the configured solver's answer
    assert controller.failures == 1
    assert controller.step(q, np.zeros(18)).ok


def test_an_infeasible_qp_is_still_named_by_daqp_whatever_the_backend(description):
    controller = WholeBodyController(solver={"backend": "osqp"},
                                     limits={"torque_limit_fraction": 0.01})
    q = description.pose("standing")
    controller.reset(q)
    out = controller.step(q, np.zeros(18))
    assert out.status is ControlStatus.RELAXED and out.infeasible_group == "torque limits"
    assert out.message.endswith("; infeasible constraint group: torque limits; commanded the "
                                "solution with that group relaxed")
    assert np.all(np.abs(out.tau) <= controller.tau_max + 1e-9)
