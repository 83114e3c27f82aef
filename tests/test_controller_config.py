"""The controller's configuration: one nested shape, its parts, the paths that reach them."""

from dataclasses import fields, replace

import pytest

from wbc import ControllerConfig, WholeBodyController
from wbc.controller.controller_config import (
    PARTS,
    PATHS,
    ContactSettings,
    CostWeights,
    LimitSettings,
    ShapingSettings,
    SolverSettings,
    TaskGains,
)
from wbc.core.errors import ConfigurationError, UnknownNameError


def test_one_shape_a_field_per_part_each_parameter_declared_once():
    assert [f.name for f in fields(ControllerConfig)] == [name for name, _ in PARTS]
    assert PATHS == tuple(f"{name}.{f.name}" for name, part in PARTS for f in fields(part))
    bare = [path.split(".")[1] for path in PATHS]
    assert len(set(bare)) == len(bare) == 39
    config = ControllerConfig()
    for name, part in PARTS:
        assert type(getattr(config, name)) is part and getattr(config, name) == part()
        for f in fields(part):  # no flat copy of a part's fields on the whole
            assert not hasattr(config, f.name)


def test_part_overrides_reach_the_parts_and_the_controller_s_pieces():
    controller = WholeBodyController(solver={"backend": "osqp"},
                                     contacts={"friction_coefficient": 0.5},
                                     gains=TaskGains(com_kp=200.0), shaping={"swing_kp": 60.0},
                                     limits={"torque_limit_fraction": 0.5})
    config = controller.config
    assert config.contacts.friction_coefficient == 0.5 == controller.balance.friction.mu
    assert config.gains.com_kp == 200.0 == controller.com_task.kp
    assert controller.backend.name == "osqp" and config.solver.backend == "osqp"
    assert controller.motor.settings is config.shaping and config.shaping.swing_kp == 60.0
    assert controller.schedule.settings is config.contacts
    assert config.limits.torque_limit_fraction == 0.5
    assert controller.tau_max == pytest.approx(0.5 * controller.description.effort_limit)
    # A mapping changes only its fields; the part's others stay those of the config given.
    base = ControllerConfig(shaping={"stance_kp": 30.0})
    assert WholeBodyController(base, shaping={"swing_kp": 60.0}).config.shaping == \
        ShapingSettings(stance_kp=30.0, swing_kp=60.0)


def test_a_config_from_parts_and_paths():
    config = ControllerConfig(gains=TaskGains(com_kp=120.0), shaping=ShapingSettings(swing_kp=70.0),
                              weights={"com_weight": 5.0})
    assert (config.gains.com_kp, config.shaping.swing_kp, config.weights.com_weight) == (
        120.0, 70.0, 5.0)
    assert config.gains == TaskGains(com_kp=120.0)
    assert config == ControllerConfig().with_values(
        {"gains.com_kp": 120.0, "shaping.swing_kp": 70.0, "weights.com_weight": 5.0})
    assert replace(config, gains=TaskGains(com_kp=1.0)).gains.com_kp == 1.0
    assert config.with_parts(gains={"foot_kp": 5.0}).gains == TaskGains(com_kp=120.0, foot_kp=5.0)
    assert ControllerConfig.path_of("swing_kp") == "shaping.swing_kp"
    with pytest.raises(ConfigurationError, match=r"^gains: expected a TaskGains or a mapping of "
                                                 r"its fields, received CostWeights$"):
        ControllerConfig(gains=CostWeights())
    with pytest.raises(UnknownNameError, match=r"^unknown task gain 'kp'; valid task gains: "):
        ControllerConfig(gains={"kp": 1.0})


def test_a_bare_name_is_refused_naming_its_path():
    with pytest.raises(UnknownNameError, match=r"^com_kp: the controller's parameters are "
                                               r"nested; it is gains\.com_kp \(gains="
                                               r"\{'com_kp': \.\.\.\} in Python, --set "
                                               r"controller\.gains\.com_kp=VALUE on the "
                                               r"command line\)$"):
        ControllerConfig(com_kp=200.0)
    with pytest.raises(ConfigurationError, match=r"^unknown controller parameter\(s\) "
                                                 r"\['backend'\]; valid controller parameters: "
                                                 r"solver, gains, weights, contacts, limits, "
                                                 r"shaping \(they are nested: backend is "
                                                 r"solver\.backend: solver=\{'backend': "):
        WholeBodyController(backend="osqp")
    with pytest.raises(UnknownNameError, match=r"^unknown controller parameter 'friction'; "
                                               r"valid controller parameters: backend, "
                                               r"eliminate_dynamics, .*, "
                                               r"friction_velocity_scale_rad_s$"):
        ControllerConfig.path_of("friction")
    with pytest.raises(UnknownNameError) as err:
        ControllerConfig.path_of("frictoin_coefficient")
    assert "(did you mean 'friction_coefficient'?)" in str(err.value)


def test_paths_unknown_are_named_with_the_nearest_and_the_valid_ones():
    with pytest.raises(UnknownNameError) as err:
        ControllerConfig().with_values({"gains.com_kpp": 1.0, "com_kp": 2.0, "x.y": 3.0})
    message = str(err.value)
    assert message.startswith(
        "unknown controller parameter(s) 'gains.com_kpp' (did you mean 'gains.com_kp'?); "
        "'com_kp' (it is gains.com_kp); 'x.y'; valid controller parameters: solver.backend, "
        "solver.eliminate_dynamics, solver.control_period_s, gains.com_kp, ")
    assert message.endswith(", shaping.friction_velocity_scale_rad_s")
    with pytest.raises(ConfigurationError, match=r"^shaping\.swing_kp: expected a value in "
                                                 r"\[0, 500\], received 600$"):
        ControllerConfig().with_values({"shaping.swing_kp": 600.0})
    with pytest.raises(ConfigurationError, match=r"^contacts\.min_normal_force_n: expected "
                                                 r"less than max_normal_force_n \(250 N\)"):
        ControllerConfig().with_values({"contacts.min_normal_force_n": 300.0})


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
    name = next(name for name, kind in PARTS if kind is part)
    with pytest.raises(ConfigurationError, match=message):
        ControllerConfig(**{name: {field: value}})


def test_a_part_names_its_own_fields_only():
    with pytest.raises(UnknownNameError, match=r"^unknown task gain 'com_weight'; valid task "
                                               r"gains: com_kp, "):
        TaskGains(com_weight=1.0)
