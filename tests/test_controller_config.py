"""The controller's configuration in parts, and the flat names that reach them."""

from dataclasses import fields, replace

import pytest

from wbc import ControllerConfig, WholeBodyController
from wbc.controller.controller_config import (
    PARTS,
    ContactSettings,
    CostWeights,
    LimitSettings,
    ShapingSettings,
    SolverSettings,
    TaskGains,
)
from wbc.core.errors import ConfigurationError, UnknownNameError


def test_the_flat_names_are_the_parts_fields_each_declared_once():
    flat = [f.name for f in fields(ControllerConfig)]
    from_parts = [f.name for _, part in PARTS for f in fields(part)]
    assert flat == from_parts and len(set(flat)) == len(flat) == 39
    config = ControllerConfig()
    for name, part in PARTS:
        value = getattr(config, name)
        assert type(value) is part
        for f in fields(part):
            assert getattr(value, f.name) == getattr(config, f.name)


def test_flat_overrides_reach_the_parts_and_the_controller_s_pieces():
    controller = WholeBodyController(backend="osqp", friction_coefficient=0.5, com_kp=200.0,
                                     swing_kp=60.0, torque_limit_fraction=0.5)
    config = controller.config
    assert config.contacts.friction_coefficient == 0.5 == controller.balance.friction.mu
    assert config.gains.com_kp == 200.0 == controller.com_task.kp
    assert controller.backend.name == "osqp" and config.solver.backend == "osqp"
    assert controller.motor.settings is config.shaping and config.shaping.swing_kp == 60.0
    assert controller.schedule.settings is config.contacts
    assert config.limits.torque_limit_fraction == 0.5
    assert controller.tau_max == pytest.approx(0.5 * controller.description.effort_limit)


def test_a_config_from_parts_and_overrides():
    config = ControllerConfig.from_parts(gains=TaskGains(com_kp=120.0),
                                         shaping=ShapingSettings(swing_kp=70.0), com_weight=5.0)
    assert (config.com_kp, config.swing_kp, config.com_weight) == (120.0, 70.0, 5.0)
    assert config.gains == TaskGains(com_kp=120.0)
    assert config == ControllerConfig(com_kp=120.0, swing_kp=70.0, com_weight=5.0)
    assert replace(config, com_kp=1.0).gains.com_kp == 1.0   # the parts follow the fields
    with pytest.raises(ConfigurationError, match=r"^gains: expected a TaskGains, received "
                                                 r"CostWeights$"):
        ControllerConfig.from_parts(gains=CostWeights())
    with pytest.raises(ConfigurationError, match=r"^unknown controller parameter\(s\) \['kp'\]"):
        ControllerConfig.from_parts(kp=1.0)


@pytest.mark.parametrize(("part", "field", "value", "message"), [
    (TaskGains, "com_kp", -1.0, r"^com_kp: expected a value in \[0, inf\], received -1$"),
    (ContactSettings, "friction_coefficient", 0.0,
     r"^friction_coefficient: expected a value in \(0, 5\], received 0$"),
    (ContactSettings, "min_normal_force_n", 300.0,
     r"^min_normal_force_n: expected less than max_normal_force_n \(250 N\), received 300 N$"),
    (LimitSettings, "torque_limit_fraction", 2.0,
     r"^torque_limit_fraction: expected a value in \(0, 1\], received 2$"),
    (ShapingSettings, "known_joint_damping", (0.1, -1.0, 0.0),
     r"^known_joint_damping \(thigh\): expected a value in \[0, 10\], received -1$"),
    (SolverSettings, "control_period_s", 1.0,
     r"^control_period_s: expected a value in \[0.0001, 0.01\], received 1$"),
])
def test_a_part_and_the_whole_name_a_bad_value_alike(part, field, value, message):
    with pytest.raises(ConfigurationError, match=message):
        part(**{field: value})
    with pytest.raises(ConfigurationError, match=message):
        ControllerConfig(**{field: value})


def test_a_part_names_its_own_fields_only():
    with pytest.raises(UnknownNameError, match=r"^unknown task gain 'com_weight'; valid task "
                                               r"gains: com_kp, "):
        TaskGains(com_weight=1.0)
