"""A sweep spec's values: ranges, lists and single values, each checked by what will use it."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

import yaml

from actions.go2.high_five_behaviour import MAX_HOLD_S
from actions.robot.robot_interface import STATE_SOURCES
from benchmarks import robustness
from sim.control_loop import PHYSICS_TIMESTEP_S
from sim.episode import episode_default
from sim.mujoco_robot import physics_steps_per_period
from sim.plant import PLANT_PRESETS, Plant
from sim.sensor_model import SENSOR_PRESETS, SensorModel
from wbc.backends.backend import available_backends
from wbc.controller.controller_config import PARTS, PATHS, ControllerConfig, ShapingSettings
from wbc.core.errors import ConfigurationError, WbcError
from wbc.core.validation import as_float
from wbc.motions.leg_lift import MAX_HEIGHT_M, MIN_HEIGHT_M


class SweepSpecError(ConfigurationError):
    """A sweep specification that cannot be run; the message names the field."""


#: The push axes every table and heat map lays out as impulse rows x direction columns.
DIRECTIONS, IMPULSES = "pushes.directions_deg", "pushes.impulses_ns"
#: Loop fields of the ``plant`` section (:class:`benchmarks.robustness.PlantCase`).
CASE_FIELDS = ("delay_ticks", "control_period_s")
#: Fields given three numbers (one value of theirs is a list).
VECTOR_FIELDS = ("payload_offset_m", *ShapingSettings.PER_JOINT_TYPE)

#: The top-level fields and their defaults (robustness's high five, the default seed).
TOP_FIELDS = {"height_m": robustness.HEIGHT_M, "hold_s": robustness.HOLD_S,
              "seed": episode_default("sensor_seed"), "metrics": True}
#: The push fields that have defaults.
PUSH_DEFAULTS = {"duration_s": robustness.PUSH_DURATION_S,
                 "into_hold_s": robustness.PUSH_INTO_HOLD_S}
#: The sections of a spec.
SECTIONS = ("pushes", "plant", "sensors", "gains")
_INT_FIELDS = {"hold_s", "seed", "plant.delay_ticks", "plant.condim"}
_BOOL_FIELDS = {"metrics", "gains.eliminate_dynamics", "sensors.foot_force_integer"}
_TEXT_FIELDS = {"plant.preset", "plant.cone", "sensors.preset", "sensors.state",
                "gains.backend"}


def valid_names(section: str) -> tuple[str, ...]:
    """The field names a section takes."""
    if section == "pushes":
        return ("directions_deg", "impulses_ns", *PUSH_DEFAULTS)
    if section == "plant":
        return ("preset", *Plant.parameter_names(), *CASE_FIELDS)
    if section == "sensors":
        return ("preset", "state", *SensorModel.parameter_names())
    return tuple(path.split(".")[1] for path in PATHS if path != "solver.control_period_s")


def _kind(path: str) -> str:
    if path in _INT_FIELDS:
        return "int"
    if path in _BOOL_FIELDS:
        return "bool"
    if path in _TEXT_FIELDS:
        return "text"
    if path.rpartition(".")[2] in VECTOR_FIELDS:
        return "vector"
    return "float"


# ---------------------------------------------------------------------------- values


def parse_values(path: str, raw: Any) -> tuple[Any, ...]:
    """The values of one field: one value, a list, or a range ``START:STOP:NUM``.

    Raises:
        SweepSpecError: An empty list or range, a malformed range, a value of the wrong type
            or the same value twice.
    """
    kind = _kind(path)
    if kind == "vector":
        if isinstance(raw, (list, tuple)) and raw and all(
                isinstance(item, (list, tuple)) for item in raw):
            items = list(raw)
        else:
            items = [raw]
    elif isinstance(raw, str) and kind in ("float", "int") and ":" in raw:
        items = _range(path, raw)
    elif isinstance(raw, (list, tuple)):
        items = list(raw)
    elif isinstance(raw, Mapping) or raw is None:
        raise SweepSpecError(
            f"{path}: expected one value, a list of values or a range START:STOP:NUM, "
            f"received {raw!r}")
    else:
        items = [raw]
    if not items or (kind == "vector" and items == [[]]):
        raise SweepSpecError(f"{path}: expected at least one value, received {raw!r}")
    values = tuple(_typed(path, kind, item) for item in items)
    repeated = sorted({repr(v) for v in values if values.count(v) > 1})
    if repeated:
        raise SweepSpecError(
            f"{path}: expected distinct values, received {raw!r} ({', '.join(repeated)} "
            f"more than once)")
    return values


def _range(path: str, text: str) -> list[float]:
    parts = text.split(":")
    usage = (f"{path}: expected a range START:STOP:NUM (NUM values from START to STOP, "
             f"e.g. 2:10:5), received {text!r}")
    if len(parts) != 3:
        raise SweepSpecError(usage)
    try:
        start, stop, count = float(parts[0]), float(parts[1]), float(parts[2])
    except ValueError:
        raise SweepSpecError(usage) from None
    if not (math.isfinite(start) and math.isfinite(stop)) or not count.is_integer():
        raise SweepSpecError(usage)
    if count < 1:
        raise SweepSpecError(
            f"{path}: expected at least one value, received {text!r} (an empty range: NUM "
            f"must be 1 or more)")
    if count == 1:
        return [start]
    step = (stop - start) / (count - 1)
    # Rounded: 0:1:11 gives 0.3, not 0.30000000000000004, in tables and keys.
    return [round(start + i * step, 12) for i in range(int(count))]


def _typed(path: str, kind: str, value: Any) -> Any:
    if kind == "text":
        if not isinstance(value, str):
            raise SweepSpecError(f"{path}: expected a name, received {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise SweepSpecError(f"{path}: expected true or false, received {value!r}")
        return value
    if kind == "vector":
        if not isinstance(value, (list, tuple)) or len(value) != 3 or not all(
                _is_number(v) for v in value):
            raise SweepSpecError(
                f"{path}: expected three numbers, or a list of such lists to sweep them, "
                f"received {value!r}")
        return tuple(float(v) for v in value)
    if not _is_number(value):
        raise SweepSpecError(
            f"{path}: expected a number, a list of numbers or a range START:STOP:NUM, "
            f"received {value!r}")
    if kind == "int":
        if not float(value).is_integer():
            raise SweepSpecError(f"{path}: expected a whole number, received {value!r}")
        return int(value)
    return float(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_value(path: str, value: Any) -> None:
    """Check one value of a field by what will use it; re-raised naming ``path``."""
    section, _, name = path.rpartition(".")
    try:
        if path == "height_m":
            as_float(path, value, low=MIN_HEIGHT_M, high=MAX_HEIGHT_M)
        elif path == "hold_s":
            as_float(path, value, low=0, high=MAX_HOLD_S)
        elif path == "seed":
            as_float(path, value, low=0)
        elif path == DIRECTIONS:
            as_float(path, value)
        elif path == IMPULSES:
            as_float(path, value, low=0.0)
        elif path == "pushes.duration_s":
            as_float(path, value, low=0.0, high=1.0, low_inclusive=False)
        elif path == "pushes.into_hold_s":
            as_float(path, value, low=0.0, high=MAX_HOLD_S)
        elif path == "plant.preset":
            if value not in PLANT_PRESETS:
                raise SweepSpecError(f"{path}: unknown plant preset {value!r}; valid presets: "
                                     f"{', '.join(PLANT_PRESETS)}")
        elif path == "plant.delay_ticks":
            as_float(path, value, low=0, high=100)
        elif path == "plant.control_period_s":
            physics_steps_per_period(value, min(PHYSICS_TIMESTEP_S, value))
        elif section == "plant":
            Plant().with_params(**{name: value})
        elif path == "sensors.preset":
            if value not in SENSOR_PRESETS:
                raise SweepSpecError(f"{path}: unknown sensor preset {value!r}; valid presets: "
                                     f"{', '.join(SENSOR_PRESETS)}")
        elif path == "sensors.state":
            if value not in STATE_SOURCES:
                raise SweepSpecError(f"{path}: unknown state source {value!r}; valid: "
                                     f"{', '.join(STATE_SOURCES)}")
        elif section == "sensors":
            SensorModel().with_params(**{name: value})
        elif path == "gains.backend":
            if value not in available_backends():
                raise SweepSpecError(f"{path}: unknown or uninstalled QP backend {value!r}; "
                                     f"installed: {', '.join(available_backends())}")
        elif section == "gains":
            part = dict(PARTS)[ControllerConfig.path_of(name).split(".")[0]]
            part(**{name: value})  # a sweep file's gains are named bare: the message too
    except SweepSpecError:
        raise
    except WbcError as err:
        raise SweepSpecError(renamed(path, str(err))) from None


def renamed(path: str, message: str) -> str:
    """``damping: expected ...`` -> ``plant.joint_damping: expected ...``."""
    if message.startswith((f"{path}:", f"{path} ")):
        return message
    head, sep, tail = message.partition(": ")
    first, _, rest = head.partition(" ")
    if sep and first.isidentifier():
        return f"{path}{' ' + rest if rest else ''}: {tail}"
    return f"{path}: {message}"


# ---------------------------------------------------------------------------- YAML


class SpecLoader(yaml.SafeLoader):
    """YAML with ranges: ``2:10:5`` stays text (YAML 1.1 reads it as 7805, base 60)."""


SpecLoader.yaml_implicit_resolvers = {
    first: list(resolvers) for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}
for _first in "+-.0123456789":
    SpecLoader.yaml_implicit_resolvers.setdefault(_first, []).insert(
        0, ("tag:yaml.org,2002:str", re.compile(r"^[-+]?[0-9.][-+0-9.eE_]*(?::[-+0-9.eE_]*)+$")))


def read_yaml(text: str) -> Any:
    """Parse a spec's YAML (see :class:`SpecLoader`)."""
    return yaml.load(text, Loader=SpecLoader)


def cli_values(text: str) -> Any:
    """A command-line value list as the YAML would give it.

    ``2:10:5`` stays a range; ``[0.05, 0, 0]`` (or ``[[...], [...]]``) is read as YAML;
    ``a,b,c`` is split at the commas, each item read as YAML (``2`` a number, ``osqp`` a
    name, ``true`` a flag).
    """
    text = text.strip()
    if text.startswith("["):
        try:
            return read_yaml(text)
        except yaml.YAMLError:
            return text
    items = [_yaml_scalar(item.strip()) for item in text.split(",")]
    return items if len(items) > 1 else items[0]


def _yaml_scalar(text: str) -> Any:
    try:
        value = read_yaml(text) if text else text
    except yaml.YAMLError:
        return text
    return text if isinstance(value, (Mapping, list)) else value
