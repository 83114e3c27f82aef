"""Tests of wbc.core.compiled_program: kernels run as one compiled call, and the tick's
program against the calls it replaces."""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
import pytest

from wbc.core.compiled_program import CompiledProgram


class Pair(NamedTuple):
    a: np.ndarray
    b: np.ndarray


@numba.njit(cache=True)
def _scale(x, y, s):
    for i in range(x.size):
        y[i] = s * x[i]


@numba.njit(cache=True)
def _total(pair, flags, strided, index):
    return pair.a.sum() + pair.b.sum() + strided.sum() + (100.0 if flags[index] else 0.0)


def test_kernels_run_in_order_on_the_arrays_as_they_are_when_called() -> None:
    x, y = np.arange(3.0), np.zeros(3)
    flags = np.array([False, True])
    strided = np.ones((2, 2))[:, 0]  # not contiguous: passed as it is
    program = CompiledProgram([(_scale, (x, y, 2.0)), (_total, (Pair(y, x), flags, strided, 1))])
    assert program.calls == 1
    assert program.run() == pytest.approx(2 * 3 + 3 + 2 + 100)
    x[:] = 1.0
    flags[1] = False
    strided[0] = 5.0  # a view of the matrix's first column
    assert program.run() == pytest.approx(2 * 3 + 3 + 6)
    np.testing.assert_array_equal(y, [2.0, 2.0, 2.0])


def test_python_steps_run_in_their_place_between_compiled_parts() -> None:
    x, y = np.arange(3.0), np.zeros(3)
    seen = []
    program = CompiledProgram([(_scale, (x, y, 2.0)), lambda: seen.append(y.copy()),
                               (_scale, (y, x, 0.5)), lambda: seen.append(x.copy())])
    assert program.calls == 4
    program.run()
    np.testing.assert_array_equal(seen[0], [0.0, 2.0, 4.0])
    np.testing.assert_array_equal(seen[1], [0.0, 1.0, 2.0])


def test_a_kernel_that_is_not_compiled_is_refused() -> None:
    with pytest.raises(TypeError, match="numba.njit function, received function"):
        CompiledProgram([(lambda x: x, (np.zeros(1),))])


@pytest.fixture(scope="module")
def controller():
    from wbc.controller.whole_body_controller import WholeBodyController

    controller = WholeBodyController()
    q = controller.description.pose("standing")
    controller.reset(q)
    rng = np.random.default_rng(3)
    v = np.zeros(controller.model.nv)
    for _ in range(5):
        controller.step(q, v + 0.05 * rng.standard_normal(v.size))
    return controller


def _qp_arrays(problem):
    return [problem.H.copy(), problem.f.copy(), problem.A.copy(), problem.lower.copy(),
            problem.upper.copy(), problem.lb.copy(), problem.ub.copy()]


@pytest.mark.slow  # builds a controller (seconds)
@pytest.mark.parametrize("lifted", [False, True])
def test_the_tick_program_builds_the_qp_the_separate_calls_build(controller, lifted) -> None:
    builder = controller.builder
    q = controller.description.pose("standing")
    v = np.linspace(-0.2, 0.2, controller.model.nv)
    if lifted:
        controller.foot_tasks["FR"].set_target(controller.foot_position("FR") + [0, 0, 0.05])
        builder.set_active(controller.foot_tasks["FR"], True)
        builder.set_loaded_contacts(["FL", "RL", "RR"])
    controller.kinematics.compute(q, v)
    builder.evaluate()
    separate = _qp_arrays(builder.assemble())
    controller.kinematics.compute(q, 0.5 * v)  # the program must not read stale values
    builder.build()
    controller.kinematics.compute(q, v)
    fused = _qp_arrays(builder.build())
    assert builder.reduced
    for a, b in zip(separate, fused):
        np.testing.assert_array_equal(a, b)
