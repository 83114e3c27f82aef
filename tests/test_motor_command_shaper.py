"""From a solved tick to the drivers' command: per-leg gains, friction feed-forward, tau."""

import numpy as np
import pytest

from wbc import WholeBodyController
from wbc.controller.controller_config import ControllerConfig, ShapingSettings
from wbc.controller.motor_command_shaper import MotorCommandShaper, joint_types
from wbc.core.compiled_program import CompiledProgram
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, Go2Description


def shaper(**overrides) -> MotorCommandShaper:
    description = Go2Description()
    effort = description.effort_limit
    return MotorCommandShaper(ShapingSettings(**overrides), control_period_s=1e-3,
                              tau_max=0.9 * effort, effort_limit=effort,
                              joint_types=joint_types(JOINT_NAMES))


def test_stance_and_swing_gains_per_leg():
    s = shaper(stance_kp=40.0, stance_kd=2.0, swing_kp=55.0, swing_kd=2.5)
    s.set_stance(Go2Description().leg_joint_indices("FR"), False)
    for i, name in enumerate(JOINT_NAMES):
        swing = name.startswith("FR")
        assert s.kp[i] == (55.0 if swing else 40.0) and s.kd[i] == (2.5 if swing else 2.0)


def test_command_is_the_qp_torque_plus_the_pd_at_the_measured_state():
    s = shaper()
    rng = np.random.default_rng(1)
    q, dq = rng.normal(size=12), rng.normal(size=12)
    s.reference.reset(q, dq)
    tau_qp = rng.uniform(-5, 5, 12)
    out = s.shape(q, dq, rng.normal(size=12), tau_qp)
    np.testing.assert_array_equal(out["tau_ff"], tau_qp)  # no friction known
    expected = tau_qp + out["kp"] * (out["q_des"] - q) + out["kd"] * (out["dq_des"] - dq)
    np.testing.assert_allclose(out["tau"], expected)


def test_known_friction_is_fed_forward_along_the_desired_velocity():
    s = shaper(known_joint_damping=(0.1, 0.2, 0.3), known_joint_friction=(0.25, 0.2, 1.0),
               friction_velocity_scale_rad_s=0.05)
    q = np.zeros(12)
    s.reference.reset(q, np.full(12, 1.0))  # moving at 1 rad/s, far above the scale
    out = s.shape(q, np.full(12, 1.0), np.zeros(12), np.zeros(12))
    dq_des = out["dq_des"]
    damping = np.tile([0.1, 0.2, 0.3], 4)
    friction = np.tile([0.25, 0.2, 1.0], 4)
    np.testing.assert_allclose(out["tau_ff"], damping * dq_des + friction * np.tanh(dq_des / 0.05))
    np.testing.assert_allclose(out["tau_ff"], damping + friction, rtol=1e-6)


def test_controller_output_is_a_motor_command_with_swing_gains_on_a_raised_leg(description):
    standing = description.pose("standing")
    controller = WholeBodyController()
    controller.reset(standing)
    out = controller.step(standing, np.zeros(18))
    assert out.ok and (out.kp == controller.config.shaping.stance_kp).all()
    np.testing.assert_allclose(out.tau, out.clipped_torque_at(
        standing[7:], np.zeros(12), controller.description.effort_limit))
    controller.schedule.set_max_normal_force("FR", 0.0)
    controller.schedule.set_swing("FR")
    out = controller.step(standing, np.zeros(18))
    fr = [i for i, name in enumerate(JOINT_NAMES) if name.startswith("FR")]
    assert (out.kp[fr] == controller.config.shaping.swing_kp).all()
    assert (out.kd[fr] == controller.config.shaping.swing_kd).all()


@pytest.mark.parametrize(("field", "value", "message"), [
    ("stance_kp", -1.0, r"stance_kp: expected a value in \[0, 500\], received -1"),
    ("swing_kd", 80.0, r"swing_kd: expected a value in \[0, 50\], received 80"),
    ("known_joint_friction", (0.2, -0.1, 1.0),
     r"known_joint_friction \(thigh\): expected a value in \[0, 10\], received -0.1"),
    ("known_joint_damping", 0.2,
     r"known_joint_damping: expected three numbers \(hip, thigh, calf\), received 0.2"),
])
def test_gains_and_known_friction_are_validated(field, value, message):
    with pytest.raises(ConfigurationError, match=message):
        ControllerConfig(shaping={field: value})


def _compiled_shaper(**overrides):
    """A shaper, its compiled step run as a program, and the input arrays it reads."""
    s = shaper(**overrides)
    inputs = [np.zeros(12) for _ in range(4)]  # q, dq, qdd, tau_qp: written in place
    return s, CompiledProgram([s.compiled_step(*inputs)]), inputs


def test_the_compiled_step_writes_what_shape_returns_through_stance_and_retune():
    settings = {"known_joint_damping": (0.1, 0.2, 0.3), "known_joint_friction": (0.25, 0.2, 1.0),
                "stance_leak_time_s": 0.05, "swing_leak_time_s": 0.0}
    plain, (compiled, program, inputs) = shaper(**settings), _compiled_shaper(**settings)
    untuned = shaper(**settings)
    rng = np.random.default_rng(3)
    fr = Go2Description().leg_joint_indices("FR")
    for tick in range(40):
        if tick == 10:
            for s in (plain, compiled, untuned):
                s.set_stance(fr, False)
        if tick == 20:  # a walk's retune: other bounds and friction scale, in place
            for s in (plain, compiled):
                s.retune(ShapingSettings(**settings, reference_position_bound_rad=0.01,
                                         friction_velocity_scale_rad_s=0.2))
        values = [rng.normal(size=12), rng.normal(size=12), 50 * rng.normal(size=12),
                  rng.uniform(-5, 5, 12)]
        for array, value in zip(inputs, values):
            array[:] = value
        expected = plain.shape(*values)
        compiled.prepare(values[0], values[1])
        program.run()
        got = compiled.command()
        for name, row in zip(("q_des", "dq_des", "kp", "kd", "tau_ff", "tau"), got):
            np.testing.assert_array_equal(row, expected[name], err_msg=f"tick {tick} {name}")
        reference = untuned.shape(*values)
        if tick >= 20:  # the retune changed the command (so the check above can fail)
            assert not np.array_equal(reference["tau_ff"], expected["tau_ff"])
    assert not np.shares_memory(got[0], compiled.command_rows)  # the caller's own arrays
