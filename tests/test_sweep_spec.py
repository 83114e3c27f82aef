"""Sweep specs: ranges, episodes and their keys, and one clear error per bad field."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks import robustness
from benchmarks.sweep_spec import (
    BUILT_IN,
    DIRECTIONS,
    IMPULSES,
    SweepSpec,
    SweepSpecError,
    parse_values,
    read_yaml,
)
from benchmarks.sweep_values import cli_values

EXAMPLES = Path(__file__).resolve().parents[1] / "benchmarks" / "sweeps"


def test_ranges_lists_and_single_values():
    assert parse_values(IMPULSES, "2:10:5") == (2.0, 4.0, 6.0, 8.0, 10.0)
    assert parse_values("plant.joint_damping", "0:1:11")[3] == 0.3  # not 0.30000000000000004
    assert parse_values("plant.joint_damping", "3:1:3") == (3.0, 2.0, 1.0)
    assert parse_values(DIRECTIONS, 45) == (45.0,)
    assert parse_values("hold_s", "1:3:3") == (1, 2, 3)
    assert parse_values("gains.backend", ["daqp", "osqp"]) == ("daqp", "osqp")
    assert parse_values("plant.payload_offset_m", [0.05, 0, 0]) == ((0.05, 0.0, 0.0),)
    assert parse_values("plant.payload_offset_m", [[0, 0, 0], [0.05, 0, 0]]) == (
        (0.0, 0.0, 0.0), (0.05, 0.0, 0.0))


def test_yaml_and_command_line_read_a_range_as_a_range():
    # YAML 1.1 reads 2:10:5 as a base-60 number (7805).
    assert read_yaml("impulses_ns: 2:10:5") == {"impulses_ns": "2:10:5"}
    assert cli_values("2:10:5") == "2:10:5"
    assert cli_values("0,45,90") == [0, 45, 90]
    assert cli_values("-2") == -2
    assert cli_values("osqp,daqp") == ["osqp", "daqp"]
    assert cli_values("[[0.05,0,0],[0,0,0]]") == [[0.05, 0, 0], [0, 0, 0]]


def test_the_quick_sweep_expands_cases_then_impulses_then_directions():
    spec = SweepSpec.load("quick")
    episodes = spec.episodes()
    assert [e.axes for e in episodes] == [
        {"plant.payload_kg": p, DIRECTIONS: d} for p in (0.0, 2.0) for d in (90.0, 315.0)]
    assert [a.path for a in spec.case_axes] == ["plant.payload_kg"]
    first = episodes[0]
    assert first.label() == "plant.payload_kg=0, pushes.directions_deg=90"
    assert first.section("gains") == {"swing_kp": 45.0}
    push = first.push()
    assert (push.direction_deg, push.impulse_ns) == (90.0, pytest.approx(8.0))
    assert push.at_s == pytest.approx(robustness.HOLD_START_S + 0.2)
    case = episodes[3].plant_case()
    assert case.plant.payload_kg == 2.0 and case.plant.payload_offset_m == (0.05, 0.0, 0.0)
    resolved = episodes[3].resolved()
    assert resolved["controller"]["swing_kp"] == 45.0
    assert resolved["controller"]["stance_kp"] == 40.0  # the defaults are part of the key
    assert resolved["plant"]["hip"]["damping"] == 2.0  # Menagerie's, from the preset
    assert len({e.key for e in episodes}) == 4


def test_keys_follow_the_full_specification_not_its_spelling():
    base = {"pushes": {"directions_deg": [0], "impulses_ns": [4]}, "gains": {"swing_kp": 50}}
    key = SweepSpec.from_mapping(base).episodes()[0].key
    same = {"pushes": {"directions_deg": 0.0, "impulses_ns": "4:4:1"},
            "gains": {"swing_kp": 50.0}}
    assert SweepSpec.from_mapping(same).episodes()[0].key == key
    other = {**base, "gains": {"swing_kp": 51}}
    assert SweepSpec.from_mapping(other).episodes()[0].key != key
    seed = {**base, "seed": 1}
    assert SweepSpec.from_mapping(seed).episodes()[0].key != key


def test_a_zero_impulse_is_no_push_in_every_direction():
    spec = SweepSpec.from_mapping({"pushes": {"directions_deg": [0, 90], "impulses_ns": [0, 4]}})
    episodes = spec.episodes()
    assert [e.push() is None for e in episodes] == [True, True, False, False]
    assert episodes[0].key == episodes[1].key != episodes[2].key
    no_push = SweepSpec.from_mapping({}).episodes()
    assert len(no_push) == 1 and no_push[0].key == episodes[0].key


def test_overrides_replace_a_field_and_are_checked():
    spec = SweepSpec.load("pushes").with_values({IMPULSES: "4:8:2", "plant.payload_kg": [0, 2],
                                                 "hold_s": 2})
    assert spec.axis(IMPULSES).values == (4.0, 8.0)
    assert spec.axis("plant.payload_kg").values == (0.0, 2.0)
    assert len(spec.episodes()) == 8 * 2 * 2
    assert SweepSpec.load("pushes").axis(IMPULSES).values == robustness.IMPULSES_NS


def test_built_in_sweeps_and_the_example_files_load():
    assert len(SweepSpec.load("pushes").episodes()) == 40
    assert len(SweepSpec.load("plant-pushes").episodes()) == 160
    assert set(BUILT_IN) == {"pushes", "plant-pushes", "quick"}
    gains = SweepSpec.load(EXAMPLES / "gains.yaml")
    assert gains.name == "gains"
    assert [a.path for a in gains.case_axes] == ["plant.delay_ticks", "gains.swing_kp",
                                                  "gains.swing_kd"]
    assert len(gains.episodes()) == 64


@pytest.mark.parametrize(("document", "message"), [
    ({"plant": {"jont_damping": 1}},
     ("plant.jont_damping: unknown plant parameter 'jont_damping'; valid: preset, joint_damping, "
      "joint_friction_loss, joint_armature, hip_damping, ")),
    ({"gains": {"com_kp": []}}, "gains.com_kp: expected at least one value, received []"),
    ({"gains": {"com_kp": "100:200:0"}},
     ("gains.com_kp: expected at least one value, received '100:200:0' (an empty range: NUM "
      "must be 1 or more)")),
    ({"pushes": {"directions_deg": [0], "impulses_ns": [4, -2]}},
     "pushes.impulses_ns: expected a value in [0, inf], received -2"),
    ({"pushes": {"directions_deg": [0]}},
     ("pushes.impulses_ns: expected with every push sweep (pushes.directions_deg and "
      "pushes.impulses_ns), received pushes with directions_deg")),
    ({"pushes": {"directions_deg": [0], "impulses_ns": "2:10"}},
     ("pushes.impulses_ns: expected a range START:STOP:NUM (NUM values from START to STOP, e.g. "
      "2:10:5), received '2:10'")),
    ({"pushes": {"directions_deg": [0, 0], "impulses_ns": 4}},
     "pushes.directions_deg: expected distinct values, received [0, 0] (0.0 more than once)"),
    ({"plant": {"joint_damping": [1, 12]}},
     "plant.joint_damping: expected a value in [0, 10], received 12"),
    ({"plant": {"preset": "go1"}},
     ("plant.preset: unknown plant preset 'go1'; valid presets: menagerie, unitree-mujoco, "
      "identified, ideal")),
    ({"plant": {"control_period_s": 0.0015}},
     "plant.control_period_s: expected a whole number of physics steps of 0.001 s"),
    ({"plant": {"payload_offset_m": [0.5, 0, 0]}},
     "plant.payload_offset_m (x): expected a value in [-0.3, 0.3], received 0.5"),
    ({"gains": {"stance_kp": "100:600:2"}},
     "gains.stance_kp: expected a value in [0, 500], received 600"),
    ({"gains": {"swing_kp": "fast"}},
     ("gains.swing_kp: expected a number, a list of numbers or a range START:STOP:NUM, received "
      "'fast'")),
    ({"gains": {"control_period_s": 0.002}},
     "gains.control_period_s: unknown controller gain 'control_period_s'; valid: backend, "),
    ({"gains": {"backend": "gurobi"}},
     "gains.backend: unknown or uninstalled QP backend 'gurobi'; installed: "),
    ({"gains": {"min_normal_force_n": [8, 100], "max_normal_force_n": [50, 250]}},
     ("gains.min_normal_force_n: expected less than max_normal_force_n (50 N), received 100 N "
      "(in the episode gains.min_normal_force_n=100, gains.max_normal_force_n=50)")),
    ({"hold_s": 1.5}, "hold_s: expected a whole number, received 1.5"),
    ({"height_m": 0.9}, "height_m: expected a value in [0.1, 0.5], received 0.9"),
    ({"metrics": "yes"}, "metrics: expected true or false, received 'yes'"),
    ({"holds": 1}, ("holds: unknown field; valid fields: height_m, hold_s, seed, metrics, "
                    "pushes, plant, sensors, gains")),
    ({"plant": [1, 2]}, "plant: expected a mapping of name: values, received [1, 2]"),
    ({"sensors": {"preset": "go1"}},
     "sensors.preset: unknown sensor preset 'go1'; valid presets: go2, exact"),
    ({"sensors": {"state": "exact"}},
     "sensors.state: unknown state source 'exact'; valid: estimate, truth"),
    ({"sensors": {"gyro_noise_rad_s": [0.01, 2]}},
     "sensors.gyro_noise_rad_s: expected a value in [0, 1], received 2"),
    ({"sensors": {"gyro": 1}},
     "sensors.gyro: unknown sensor parameter 'gyro'; valid: preset, state, gyro_noise_rad_s, "),
    ({"plant": {"position_noise_rad": 0.01}},
     "plant.position_noise_rad: unknown plant parameter 'position_noise_rad'; valid: "),
])
def test_a_bad_spec_raises_one_error_naming_the_field(document, message):
    with pytest.raises(SweepSpecError) as caught:
        SweepSpec.from_mapping(document)
    assert str(caught.value).startswith(message), str(caught.value)


def test_the_sensors_section_reaches_the_episode_and_its_key():
    spec = SweepSpec.from_mapping({"sensors": {"preset": "exact", "state": ["estimate", "truth"],
                                               "gyro_noise_rad_s": 0.01}})
    estimate, truth = spec.episodes()
    case = estimate.plant_case()
    assert case.state == "estimate" and truth.plant_case().state == "truth"
    model = case.sensor_model()
    assert model.name == "exact + gyro_noise_rad_s=0.01" and model.gyro_noise_rad_s == 0.01
    assert estimate.resolved()["sensors"]["state"] == "estimate"
    assert estimate.key != truth.key


def test_a_bad_override_names_its_field():
    with pytest.raises(SweepSpecError, match=r"^pushes\.impulses_ns: expected a value in "
                                             r"\[0, inf\], received -2$"):
        SweepSpec.load("quick").with_values({IMPULSES: -2})


def test_a_missing_file_lists_the_built_in_sweeps(tmp_path):
    with pytest.raises(SweepSpecError, match="^spec: cannot read '.*nowhere.yaml' \\(No such "
                                             "file or directory\\); expected a YAML file or a "
                                             "built-in sweep: pushes, plant-pushes, quick$"):
        SweepSpec.load(tmp_path / "nowhere.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("pushes: [unclosed\n")
    with pytest.raises(SweepSpecError, match="^spec: '.*bad.yaml' is not valid YAML"):
        SweepSpec.load(bad)
