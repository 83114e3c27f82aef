"""Sweep specifications: ranges of pushes, plant parameters and gains, expanded into episodes.

A sweep is the product of every field's values. Written in YAML (or built from the command
line with the same syntax)::

    hold_s: 1                     # the high five's hold [s]; also height_m, seed, metrics
    pushes:                       # optional: without it, no push
      directions_deg: [0, 90, 180, 270]
      impulses_ns: "2:10:5"       # START:STOP:NUM, NUM values from START to STOP
      duration_s: 0.1             # optional; into_hold_s (default 0.2) too
    plant:                        # optional: the simulated GO2 (sim.plant.Plant), delay, rate
      preset: menagerie
      payload_offset_m: [0.05, 0, 0]
      payload_kg: [0, 2]
      delay_ticks: [0, 2]
    sensors:                      # optional: what it measures (sim.sensors.SensorModel)
      preset: go2                 # and where the controller's state comes from:
      state: estimate             # estimate (default) or truth
      gyro_noise_rad_s: [0.004, 0.02]
    gains:                        # optional: wbc.ControllerConfig fields
      swing_kp: [40, 50, 60]

A value is one value, a list of values or a range ``START:STOP:NUM``; three-number fields
(``payload_offset_m``, ``known_joint_damping``...) take a list of three numbers, or a list of
such lists to sweep them. Every value is checked when the spec is read (by
:class:`sim.plant.Plant` and :class:`wbc.ControllerConfig` for theirs), and a bad one raises
one :class:`SweepSpecError` naming the field, what it received and what is valid.

Each :class:`EpisodeSpec` has a :attr:`~EpisodeSpec.key`: a hash of its full specification,
resolved (every plant and controller parameter, defaults included), so that a result file can
tell which episodes it already holds.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import yaml

from actions.go2.high_five_behaviour import MAX_HOLD_S
from actions.robot.robot_interface import STATE_SOURCES
from benchmarks import robustness
from benchmarks.robustness import PlantCase, hold_push
from sim.control_loop import PHYSICS_TIMESTEP_S
from sim.disturbances import Push
from sim.mujoco_robot import physics_steps_per_period
from sim.plant import PLANT_PRESETS, Plant
from sim.sensors import DEFAULT_SENSORS, SENSOR_PRESETS, SensorModel
from wbc.backends.backend import available_backends
from wbc.controller.controller_config import ControllerConfig
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
VECTOR_FIELDS = ("payload_offset_m", *ControllerConfig.PER_JOINT_TYPE)

_TOP = {"height_m": robustness.HEIGHT_M, "hold_s": robustness.HOLD_S, "seed": 0,
        "metrics": True}
_PUSH_DEFAULTS = {"duration_s": robustness.PUSH_DURATION_S,
                  "into_hold_s": robustness.PUSH_INTO_HOLD_S}
_SECTIONS = ("pushes", "plant", "sensors", "gains")
_INT_FIELDS = {"hold_s", "seed", "plant.delay_ticks", "plant.condim"}
_BOOL_FIELDS = {"metrics", "gains.eliminate_dynamics", "sensors.foot_force_integer"}
_TEXT_FIELDS = {"plant.preset", "plant.cone", "sensors.preset", "sensors.state",
                "gains.backend"}


def _valid_names(section: str) -> tuple[str, ...]:
    if section == "pushes":
        return ("directions_deg", "impulses_ns", *_PUSH_DEFAULTS)
    if section == "plant":
        return ("preset", *Plant.parameter_names(), *CASE_FIELDS)
    if section == "sensors":
        return ("preset", "state", *SensorModel.parameter_names())
    return tuple(f.name for f in dataclasses.fields(ControllerConfig)
                 if f.name != "control_period_s")


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


def _check_value(path: str, value: Any) -> None:
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
            ControllerConfig(**{name: value})
    except SweepSpecError:
        raise
    except WbcError as err:
        raise SweepSpecError(_renamed(path, str(err))) from None


def _renamed(path: str, message: str) -> str:
    """``damping: expected ...`` -> ``plant.joint_damping: expected ...``."""
    if message.startswith((f"{path}:", f"{path} ")):
        return message
    head, sep, tail = message.partition(": ")
    first, _, rest = head.partition(" ")
    if sep and first.isidentifier():
        return f"{path}{' ' + rest if rest else ''}: {tail}"
    return f"{path}: {message}"


# ---------------------------------------------------------------------------- the spec


@dataclass(frozen=True)
class Axis:
    """One field of a sweep and its values (one value: a setting; more: a swept axis)."""

    path: str
    values: tuple[Any, ...]

    @property
    def swept(self) -> bool:
        """More than one value."""
        return len(self.values) > 1


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep: every field with its values; :meth:`episodes` is their product.

    Build one with :meth:`from_mapping` (a parsed YAML document), :meth:`load` (a YAML file
    or a built-in name from :data:`BUILT_IN`) and :meth:`with_values` (command-line ranges).
    """

    name: str
    #: The document it was read from (with the overrides applied).
    document: Mapping[str, Any] = field(repr=False)
    axes: tuple[Axis, ...]

    @classmethod
    def from_mapping(cls, document: Mapping[str, Any], *, name: str = "sweep") -> SweepSpec:
        """Check ``document`` (see the module docstring for its fields).

        Raises:
            SweepSpecError: The first bad field, named with its section (``plant.payload_kg``).
        """
        if not isinstance(document, Mapping):
            raise SweepSpecError(f"spec: expected a mapping of fields (height_m, hold_s, seed, "
                                 f"metrics, {', '.join(_SECTIONS)}), received {document!r}")
        valid_top = (*_TOP, *_SECTIONS)
        for key in document:
            if key not in valid_top:
                raise SweepSpecError(f"{key}: unknown field; valid fields: "
                                     f"{', '.join(valid_top)}")
        raw: dict[str, Any] = {key: document.get(key, default) for key, default in _TOP.items()}
        for section in _SECTIONS:
            entries = document.get(section)
            if entries is None:
                continue
            if not isinstance(entries, Mapping):
                raise SweepSpecError(f"{section}: expected a mapping of name: values, received "
                                     f"{entries!r}")
            valid = _valid_names(section)
            for key, value in entries.items():
                if key not in valid:
                    what = {"pushes": "push field", "plant": "plant parameter",
                            "sensors": "sensor parameter", "gains": "controller gain"}[section]
                    hint = ("; the control period is plant.control_period_s"
                            if key == "control_period_s" else "")
                    raise SweepSpecError(f"{section}.{key}: unknown {what} {key!r}; valid: "
                                         f"{', '.join(valid)}{hint}")
                raw[f"{section}.{key}"] = value
            if section == "pushes":
                missing = [k for k in ("directions_deg", "impulses_ns") if k not in entries]
                if missing:
                    raise SweepSpecError(
                        f"pushes.{missing[0]}: expected with every push sweep (pushes.directions"
                        f"_deg and pushes.impulses_ns), received pushes with "
                        f"{', '.join(entries) or 'no fields'}")
                for key, default in _PUSH_DEFAULTS.items():
                    raw.setdefault(f"pushes.{key}", default)
        axes = []
        for path, value in raw.items():
            values = parse_values(path, value)
            for item in values:
                _check_value(path, item)
            axes.append(Axis(path, values))
        spec = cls(name=name, document=dict(document), axes=tuple(axes))
        spec.episodes()  # every combination resolves (e.g. min < max normal force)
        return spec

    @classmethod
    def load(cls, source: str | Path) -> SweepSpec:
        """A spec from a YAML file, or a built-in one by name (:data:`BUILT_IN`)."""
        text = str(source)
        if text in BUILT_IN:
            return cls.from_mapping(BUILT_IN[text], name=text)
        path = Path(source)
        try:
            document = read_yaml(path.read_text())
        except OSError as err:
            raise SweepSpecError(
                f"spec: cannot read {text!r} ({err.strerror or err}); expected a YAML file or "
                f"a built-in sweep: {', '.join(BUILT_IN)}") from None
        except yaml.YAMLError as err:
            raise SweepSpecError(f"spec: {text!r} is not valid YAML: {err}") from None
        return cls.from_mapping(document or {}, name=path.stem)

    def with_values(self, overrides: Mapping[str, Any]) -> SweepSpec:
        """This spec with fields replaced: ``{"pushes.impulses_ns": "2:10:5", ...}``."""
        document = {key: dict(value) if isinstance(value, Mapping) else value
                    for key, value in self.document.items()}
        for path, value in overrides.items():
            section, _, name = path.rpartition(".")
            if section:
                if section not in _SECTIONS:
                    raise SweepSpecError(f"{path}: unknown field; valid sections: "
                                         f"{', '.join(_SECTIONS)}")
                entries = document.get(section)
                document[section] = {**(entries if isinstance(entries, Mapping) else {}),
                                     name: value}
            else:
                document[name] = value
        return SweepSpec.from_mapping(document, name=self.name)

    def axis(self, path: str) -> Axis | None:
        """The field ``path`` (``None`` when the spec does not have it)."""
        return next((a for a in self.axes if a.path == path), None)

    @property
    def swept(self) -> tuple[Axis, ...]:
        """The fields with more than one value."""
        return tuple(a for a in self.axes if a.swept)

    @property
    def case_axes(self) -> tuple[Axis, ...]:
        """The swept fields other than the push direction and impulse."""
        return tuple(a for a in self.swept if a.path not in (DIRECTIONS, IMPULSES))

    def episodes(self) -> list[EpisodeSpec]:
        """One spec per combination: cases (in field order), then impulse, then direction."""
        ordered = [a for a in self.axes if a.path not in (DIRECTIONS, IMPULSES)]
        ordered += [a for a in (self.axis(IMPULSES), self.axis(DIRECTIONS)) if a is not None]
        swept = tuple(a.path for a in ordered if a.swept)
        episodes = []
        for combination in itertools.product(*(a.values for a in ordered)):
            values = tuple(zip((a.path for a in ordered), combination))
            episode = EpisodeSpec(values, swept=swept)
            try:
                episode.key  # noqa: B018  (resolves the plant and the controller's config)
            except WbcError as err:
                raise SweepSpecError(
                    f"{_renamed(_culprit(str(err), episode), str(err))} (in the episode "
                    f"{episode.label() or 'of this spec'})") from None
            episodes.append(episode)
        return episodes


def _culprit(message: str, episode: EpisodeSpec) -> str:
    """The field a combination's error names (only the controller's fields depend on others)."""
    name = message.partition(":")[0]
    return next((p for p, _ in episode.values if p.rpartition(".")[2] == name),
                f"gains.{name}" if name.isidentifier() else "gains")


# ---------------------------------------------------------------------------- one episode


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything one episode of a sweep needs, as ``(field path, value)`` pairs."""

    values: tuple[tuple[str, Any], ...]
    #: The fields that the sweep varies (they label the episode in tables and plots).
    swept: tuple[str, ...] = field(default=(), compare=False)

    def get(self, path: str, default: Any = None) -> Any:
        """The value of ``path`` (``default`` when the sweep does not set it)."""
        return next((v for p, v in self.values if p == path), default)

    def section(self, name: str) -> dict[str, Any]:
        """The fields of one section (``plant``, ``gains``), by their names."""
        prefix = f"{name}."
        return {p[len(prefix):]: v for p, v in self.values if p.startswith(prefix)}

    @property
    def axes(self) -> dict[str, Any]:
        """The swept fields' values of this episode."""
        return {p: v for p, v in self.values if p in self.swept}

    def label(self) -> str:
        """``plant.payload_kg=2, pushes.impulses_ns=8`` (the swept fields)."""
        return ", ".join(f"{p}={value_text(v)}" for p, v in self.axes.items())

    def plant_case(self) -> PlantCase:
        """The plant, sensors, state source and control period."""
        plant = self.section("plant")
        base = Plant.preset(plant.pop("preset", "menagerie"))
        case = {k: plant.pop(k) for k in CASE_FIELDS if k in plant}
        sensors = self.section("sensors")
        model = SensorModel.preset(sensors.pop("preset", DEFAULT_SENSORS))
        state = sensors.pop("state", "estimate")
        return PlantCase(name=self.label() or "sweep",
                         plant=base.with_params(**dict(sorted(plant.items()))),
                         sensors=model.with_params(**dict(sorted(sensors.items()))),
                         state=state, **case)

    def push(self) -> Push | None:
        """The push during the hold (``None`` without one, or for a zero impulse)."""
        impulse = self.get(IMPULSES)
        if not impulse:
            return None
        return hold_push(self.get(DIRECTIONS), impulse, duration_s=self.get("pushes.duration_s"),
                         into_hold_s=self.get("pushes.into_hold_s"))

    def resolved(self) -> dict[str, Any]:
        """The full specification: every parameter the episode's result depends on.

        Raises:
            ConfigurationError: The plant or controller parameters do not go together.
        """
        case = self.plant_case()
        config = ControllerConfig(control_period_s=case.control_period_s,
                                  **self.section("gains"))
        push = self.push()
        return {
            "goal": {"target_height_m": self.get("height_m"), "hold_s": self.get("hold_s")},
            "seed": self.get("seed"), "metrics": self.get("metrics"),
            "push": None if push is None else dataclasses.asdict(push),
            "plant": dataclasses.asdict(case.plant),
            "delay_ticks": case.delay_ticks,
            "sensors": {**case.sensor_model().as_dict(), "state": case.state},
            "control_period_s": case.control_period_s,
            "controller": {f.name: getattr(config, f.name)
                           for f in dataclasses.fields(ControllerConfig)},
            "episode": {"settle_s": robustness.SETTLE_S, "after_s": robustness.AFTER_S,
                        "timeout_s": robustness.TIMEOUT_S},
        }

    @cached_property
    def key(self) -> str:
        """SHA-256 of the canonical JSON of :meth:`resolved`: equal keys, equal episodes."""
        return hashlib.sha256(canonical_json(self.resolved()).encode()).hexdigest()

    def run(self) -> dict[str, Any]:
        """Run the episode (:func:`benchmarks.robustness.run_episode`); returns its row."""
        return robustness.run_episode(
            self.plant_case(), push=self.push(), hold_s=self.get("hold_s"),
            height_m=self.get("height_m"), seed=self.get("seed"),
            measure=self.get("metrics"), gains=self.section("gains"))


def canonical_json(value: Any) -> str:
    """Sorted keys, no spaces, tuples as lists and every number a float (``2`` is ``2.0``)."""
    return json.dumps(_floats(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


def _floats(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): _floats(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_floats(v) for v in value]
    if isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    return value


def value_text(value: Any) -> str:
    """A field value as tables and plots show it (``2``, ``0.05``, ``(0.05, 0, 0)``)."""
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "(" + ", ".join(value_text(v) for v in value) + ")"
    return str(value)


# ---------------------------------------------------------------------------- built-in sweeps

_ALL_DIRECTIONS = list(robustness.DIRECTIONS_DEG)

#: Sweeps run by name (``python -m benchmarks.sweep NAME``).
BUILT_IN: dict[str, dict[str, Any]] = {
    # The README's push grid: 8 directions x 5 impulses on the Menagerie plant (40 episodes).
    "pushes": {"metrics": False,
               "pushes": {"directions_deg": _ALL_DIRECTIONS,
                          "impulses_ns": list(robustness.IMPULSES_NS)}},
    # The push grid on four plants: Menagerie's joints and with damping 3 N m s/rad, each
    # without and with a 2 kg payload 5 cm in front of the base's centre (160 episodes).
    "plant-pushes": {"pushes": {"directions_deg": _ALL_DIRECTIONS,
                                "impulses_ns": list(robustness.IMPULSES_NS)},
                     "plant": {"preset": "menagerie", "payload_offset_m": [0.05, 0.0, 0.0],
                               "joint_damping": [2.0, 3.0], "payload_kg": [0.0, 2.0]}},
    # Two pushes of 8 N s (one absorbed, one the robot steps out of) x payload {0, 2 kg},
    # with a non-default gain: 4 episodes, about 10 s of CPU.
    "quick": {"pushes": {"directions_deg": [90, 315], "impulses_ns": [8.0]},
              "plant": {"payload_offset_m": [0.05, 0.0, 0.0], "payload_kg": [0.0, 2.0]},
              "gains": {"swing_kp": 45.0}},
}
#: The sweep run when none is named.
DEFAULT_SWEEP = "plant-pushes"


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
