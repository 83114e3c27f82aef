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
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import yaml

from benchmarks import robustness
from benchmarks.plant_cases import PlantCase, controller_parts
from benchmarks.sweep_values import (
    CASE_FIELDS,
    DIRECTIONS,
    IMPULSES,
    PUSH_DEFAULTS,
    SECTIONS,
    TOP_FIELDS,
    SweepSpecError,
    check_value,
    parse_values,
    read_yaml,
    renamed,
    valid_names,
)
from sim.disturbances import Push
from sim.episode import Episode, episode_default
from sim.plant import Plant
from sim.sensor_model import SensorModel
from wbc.controller.controller_config import PARTS, ControllerConfig
from wbc.core.errors import WbcError

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
                                 f"metrics, {', '.join(SECTIONS)}), received {document!r}")
        valid_top = (*TOP_FIELDS, *SECTIONS)
        for key in document:
            if key not in valid_top:
                raise SweepSpecError(f"{key}: unknown field; valid fields: "
                                     f"{', '.join(valid_top)}")
        raw: dict[str, Any] = {key: document.get(key, default)
                               for key, default in TOP_FIELDS.items()}
        for section in SECTIONS:
            entries = document.get(section)
            if entries is None:
                continue
            if not isinstance(entries, Mapping):
                raise SweepSpecError(f"{section}: expected a mapping of name: values, received "
                                     f"{entries!r}")
            valid = valid_names(section)
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
                for key, default in PUSH_DEFAULTS.items():
                    raw.setdefault(f"pushes.{key}", default)
        axes = []
        for path, value in raw.items():
            values = parse_values(path, value)
            for item in values:
                check_value(path, item)
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
                if section not in SECTIONS:
                    raise SweepSpecError(f"{path}: unknown field; valid sections: "
                                         f"{', '.join(SECTIONS)}")
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
                    f"{renamed(_culprit(str(err), episode), str(err))} (in the episode "
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
        base = Plant.preset(plant.pop("preset", episode_default("plant")))
        case = {k: plant.pop(k) for k in CASE_FIELDS if k in plant}
        sensors = self.section("sensors")
        model = SensorModel.preset(sensors.pop("preset", episode_default("sensors")))
        state = sensors.pop("state", episode_default("state"))
        return PlantCase(name=self.label() or "sweep",
                         plant=base.with_params(**dict(sorted(plant.items()))),
                         sensors=model.with_params(**dict(sorted(sensors.items()))),
                         state=state, **case)

    def push(self) -> Push | None:
        """The push during the hold (``None`` without one, or for a zero impulse)."""
        impulse = self.get(IMPULSES)
        if not impulse:
            return None
        return robustness.hold_push(self.get(DIRECTIONS), impulse,
                                    duration_s=self.get("pushes.duration_s"),
                                    into_hold_s=self.get("pushes.into_hold_s"))

    def episode(self) -> Episode:
        """The episode :meth:`run` runs."""
        return robustness.high_five_episode(
            self.plant_case(), push=self.push(), hold_s=self.get("hold_s"),
            height_m=self.get("height_m"), seed=self.get("seed"), gains=self.section("gains"))

    def resolved(self) -> dict[str, Any]:
        """The full specification: every parameter the episode's result depends on.

        Raises:
            ConfigurationError: The plant or controller parameters do not go together.
        """
        case = self.plant_case()
        config = ControllerConfig(**controller_parts(self.section("gains"),
                                                     control_period_s=case.control_period_s))
        push = self.push()
        episode = self.episode()
        return {
            "goal": {"target_height_m": self.get("height_m"), "hold_s": self.get("hold_s")},
            "seed": self.get("seed"), "metrics": self.get("metrics"),
            "push": None if push is None else dataclasses.asdict(push),
            "plant": dataclasses.asdict(case.plant),
            "delay_ticks": case.delay_ticks,
            "sensors": {**case.sensor_model().as_dict(), "state": case.state},
            "control_period_s": case.control_period_s,
            "controller": {f.name: getattr(getattr(config, part), f.name)
                           for part, kind in PARTS for f in dataclasses.fields(kind)},
            "episode": {"settle_s": episode.settle_s, "after_s": episode.after_s,
                        "timeout_s": episode.timeout_s},
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
