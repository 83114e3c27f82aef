"""A task written in user code joins the QP and changes the motion; the tick stays correct."""

import importlib.util
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from tasks import Constraint, RobotKinematics, Task
from tests.conftest import random_configuration
from wbc import WholeBodyController
from wbc.backends import INFINITY
from wbc.core.errors import ConfigurationError

_PATH = Path(__file__).resolve().parents[1] / "examples" / "custom_task.py"
_SPEC = importlib.util.spec_from_file_location("custom_task_example", _PATH)
example = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(example)


def test_the_example_task_raises_the_base_on_the_default_plant():
    summary = example.run(raise_m=0.04, ramp_s=0.5, settle_s=0.5)
    assert summary["failures"] == 0
    assert summary["max_violation"] < 1e-6
    assert abs(summary["end_m"] - summary["target_m"]) < 0.004
    # Without the task the same script leaves the base where it was.
    control = example.run(raise_m=0.04, ramp_s=0.5, settle_s=0.5, with_task=False)
    assert control["failures"] == 0
    assert abs(control["end_m"] - control["start_m"]) < 0.003


def test_the_example_task_jacobian_and_drift_against_finite_differences(model):
    task = example.BaseHeightTask()
    task.set_target(0.3)
    kinematics = RobotKinematics(model, ("base",))
    task.bind(kinematics)
    rng = np.random.default_rng(0)
    h = 1e-6

    def height(qq):
        data = model.createData()
        pin.framesForwardKinematics(model, data, qq)
        return data.oMf[model.getFrameId("base")].translation[2]

    def rate(qq, v):
        kinematics.compute(qq, v)
        task.evaluate(kinematics)
        return task.jacobian @ v

    for _ in range(5):
        q = random_configuration(model, rng, scale=0.5)
        v = rng.normal(size=model.nv)
        plus, minus = pin.integrate(model, q, h * v), pin.integrate(model, q, -h * v)
        kinematics.compute(q, v)
        task.evaluate(kinematics)
        jv, drift = (task.jacobian @ v).copy(), task.drift.copy()
        np.testing.assert_allclose(jv, (height(plus) - height(minus)) / (2 * h), atol=1e-6)
        np.testing.assert_allclose(drift, (rate(plus, v) - rate(minus, v)) / (2 * h), atol=1e-4)


class _CalfTask(Task):
    dim = 1
    frames = ("FR_calf",)

    def __init__(self):
        super().__init__(kp=10.0)

    def compute(self, kinematics):
        self.error[0] = 0.0


def test_registration_errors_name_the_problem():
    controller = WholeBodyController()
    with pytest.raises(ConfigurationError, match=r"frames \['FR_calf'\] are not computed.*"
                                                 r"extra_frames"):
        controller.add_task(_CalfTask())
    with pytest.raises(ConfigurationError, match="extra_frames: unknown frame 'hand'"):
        WholeBodyController(extra_frames=("hand",))
    with pytest.raises(ConfigurationError, match="expected a tasks.Task, received str"):
        controller.add_task("height")
    with pytest.raises(ConfigurationError, match="ComTask is built in"):
        controller.remove_task(controller.com_task)
    task = example.BaseHeightTask()
    controller.add_task(task)
    with pytest.raises(ConfigurationError, match="BaseHeightTask is already registered"):
        controller.add_task(task)
    controller.remove_task(task)
    assert task not in controller.tasks
    ok = WholeBodyController(extra_frames=("FR_calf",))
    ok.add_task(_CalfTask())


class _ComAccelerationAtLeast(Constraint):
    """The CoM's world x acceleration [m/s^2] at least ``minimum``: one row on qdd."""

    name = "com acceleration"

    def __init__(self, minimum):
        self.minimum = minimum

    def rows(self, layout):
        return 1

    def write(self, kinematics, layout, block):
        block.A[0, :layout.nv] = kinematics.com_jacobian[0]
        block.lower[0] = self.minimum - kinematics.com_drift[0]
        block.upper[0] = INFINITY


@pytest.mark.parametrize("eliminate", [True, False])
def test_a_user_constraint_binds_in_the_reduced_and_the_full_qp(description, eliminate):
    controller = WholeBodyController(solver={"eliminate_dynamics": eliminate})
    q = description.pose("standing")
    controller.reset(q)
    free = controller.step(q, np.zeros(18))
    com_acceleration = controller.kinematics.com_jacobian[0] @ free.qdd
    assert abs(com_acceleration) < 0.1    # holding still: no reason to accelerate
    controller.add_constraint(_ComAccelerationAtLeast(0.5))
    out = controller.step(q, np.zeros(18))
    assert out.ok, out.message
    assert controller.builder.reduced is eliminate
    com_acceleration = (controller.kinematics.com_jacobian[0] @ out.qdd
                        + controller.kinematics.com_drift[0])
    assert com_acceleration == pytest.approx(0.5, abs=1e-6)   # active, and satisfied
    eq, ineq = controller.problem.violations(controller.last_solution)
    assert eq < 1e-8 and ineq < 1e-8
    assert "com acceleration" in controller.problem.row_groups


def test_a_constraint_written_for_the_old_update_name_is_refused_naming_write():
    with pytest.raises(TypeError, match=r"_Old\.update: .* write\(kinematics, layout, block\)"):
        class _Old(Constraint):
            def update(self, kinematics, layout, block):
                pass


@pytest.mark.slow  # two controllers (seconds)
def test_the_compiled_example_task_gives_the_python_one_s_torques_inside_the_tick_program():
    taus, calls = [], []
    for task_type in (example.BaseHeightTask, example.CompiledBaseHeightTask):
        controller = WholeBodyController()
        task = controller.add_task(task_type())
        q = controller.description.pose("standing")
        controller.reset(q)
        task.set_target(float(q[2]) + 0.02, 0.01)
        v = np.linspace(-0.1, 0.1, controller.model.nv)
        taus.append([controller.step(q, v).tau for _ in range(3)])
        calls.append(controller.builder.plan.last_program.calls)
    np.testing.assert_allclose(taus[0], taus[1], rtol=0.0, atol=1e-12)
    # The Python task runs between two compiled calls; the compiled one inside the one call.
    assert calls == [3, 1]
