"""The DAQP backend: its direct C call gives the wrapper's solutions, steps aside when it must."""

import importlib.metadata

import numpy as np
import pytest

from tests.conftest import random_configuration
from wbc import WholeBodyController
from wbc.backends import QpProblem, daqp_backend
from wbc.backends.daqp_backend import DaqpBackend

pytest.importorskip("daqp")


def lift_problems(description, model, count=12):
    """Reduced QPs of the controller: four feet, then FR in swing, at perturbed states."""
    rng = np.random.default_rng(5)
    standing = description.pose("standing")
    controller = WholeBodyController()
    controller.reset(standing)
    problems = []
    for i in range(count):
        if i == count // 2:
            controller.schedule.set_max_normal_force("FR", 0.0)
            controller.schedule.set_swing("FR")
        q = random_configuration(model, rng, scale=0.05, base=standing)
        out = controller.step(q, 0.2 * rng.normal(size=18))
        assert out.ok, out.message
        problems.append(controller.builder.assemble().copy())
    return problems


def test_direct_call_is_used_on_the_pinned_release():
    backend = DaqpBackend()
    problem = QpProblem(2, 0)
    problem.H[:] = np.eye(2)
    assert backend.solve(problem).found
    assert backend.uses_direct_call


def test_direct_call_gives_the_wrapper_solution(description, model):
    direct, wrapper = DaqpBackend(), DaqpBackend(direct=False)
    for problem in lift_problems(description, model):
        a, b = direct.solve(problem), wrapper.solve(problem)
        assert direct.uses_direct_call and not wrapper.uses_direct_call
        assert a.found and b.found
        assert a.iterations == b.iterations
        np.testing.assert_array_equal(a.x, b.x)


def test_infeasible_problem_fails_the_same_way():
    problem = QpProblem(2, 2)
    problem.H[:] = np.eye(2)
    problem.A[:] = [[1.0, 1.0], [1.0, 1.0]]
    problem.lower[:], problem.upper[:] = [1.0, -np.inf], [np.inf, 0.0]  # x1 + x2 >= 1 and <= 0
    direct, wrapper = DaqpBackend(), DaqpBackend(direct=False)
    a, b = direct.solve(problem), wrapper.solve(problem)
    assert not a.found and not b.found
    assert a.status == b.status == "infeasible"
    assert a.reason == "DAQP: infeasible"


def test_solution_is_the_callers_to_keep():
    backend = DaqpBackend()
    problem = QpProblem(2, 0)
    problem.H[:] = np.eye(2)
    problem.f[:] = [-1.0, -2.0]
    first = backend.solve(problem).x
    problem.f[:] = [-3.0, -4.0]
    second = backend.solve(problem).x
    np.testing.assert_allclose(first, [1.0, 2.0])
    np.testing.assert_allclose(second, [3.0, 4.0])


def test_an_array_replaced_on_the_problem_is_followed():
    backend = DaqpBackend()
    problem = QpProblem(2, 0)
    problem.H[:] = np.eye(2)
    problem.f[:] = [-1.0, -2.0]
    backend.solve(problem)
    problem.f = np.array([-5.0, -6.0])  # a new array, same structure version
    np.testing.assert_allclose(backend.solve(problem).x, [5.0, 6.0])


def test_another_release_goes_through_the_wrapper(monkeypatch):
    monkeypatch.setattr(DaqpBackend, "_direct_ok", None)
    real = importlib.metadata.version
    monkeypatch.setattr(daqp_backend.importlib.metadata, "version",
                        lambda name: "0.12.0" if name == "daqp" else real(name))
    backend = DaqpBackend()
    problem = QpProblem(2, 0)
    problem.H[:] = np.eye(2)
    problem.f[:] = [-1.0, -2.0]
    result = backend.solve(problem)
    assert result.found and not backend.uses_direct_call
    np.testing.assert_allclose(result.x, [1.0, 2.0])


def _unit_problem(n: int, f: list[float]) -> QpProblem:
    problem = QpProblem(n, 0)
    problem.H[:] = np.eye(n)
    problem.f[:] = f
    return problem


def test_each_problem_keeps_its_structures_across_switches(monkeypatch):
    backend = DaqpBackend()
    setups = []
    setup = DaqpBackend.setup
    monkeypatch.setattr(DaqpBackend, "setup", lambda self, p: (setups.append(p), setup(self, p)))
    four, three = _unit_problem(2, [-1.0, -2.0]), _unit_problem(3, [-1.0, -2.0, -3.0])
    for _ in range(3):  # feet down, foot up, ... as a controller's layouts switch
        np.testing.assert_allclose(backend.solve(four).x, [1.0, 2.0])
        np.testing.assert_allclose(backend.solve(three).x, [1.0, 2.0, 3.0])
    assert setups == [four, three]


def test_prepare_builds_a_problem_without_changing_the_current_one(monkeypatch):
    backend = DaqpBackend()
    current, other = _unit_problem(2, [-1.0, -2.0]), _unit_problem(3, [-3.0, -2.0, -1.0])
    backend.solve(current)
    backend.prepare(other)
    setups = []
    monkeypatch.setattr(DaqpBackend, "setup", lambda self, p: setups.append(p))
    np.testing.assert_allclose(backend.solve(current).x, [1.0, 2.0])
    np.testing.assert_allclose(backend.solve(other).x, [3.0, 2.0, 1.0])
    assert setups == []


def test_a_changed_structure_or_setup_builds_anew():
    backend = DaqpBackend()
    problem = QpProblem(2, 1)
    problem.H[:] = np.eye(2)
    problem.A[:] = [[1.0, 1.0]]
    problem.lower[:], problem.upper[:] = [-np.inf], [np.inf]
    problem.f[:] = [-1.0, -2.0]
    np.testing.assert_allclose(backend.solve(problem).x, [1.0, 2.0])
    problem.is_equality[:] = True  # x1 + x2 = 0 now
    problem.lower[:], problem.upper[:] = [0.0], [0.0]
    problem.structure_version += 1
    np.testing.assert_allclose(backend.solve(problem).x, [-0.5, 0.5], atol=1e-12)


def test_it_keeps_a_bounded_number_of_problems():
    backend = DaqpBackend()
    problems = [_unit_problem(2, [-1.0, -float(k)]) for k in range(40)]
    for k, problem in enumerate(problems):
        np.testing.assert_allclose(backend.solve(problem).x, [1.0, float(k)])
    assert len(backend._states) <= daqp_backend._KEPT_PROBLEMS
    np.testing.assert_allclose(backend.solve(problems[0]).x, [1.0, 0.0])  # evicted: rebuilt
