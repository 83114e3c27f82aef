"""Every gain, weight, limit and choice of the whole-body controller, validated, in parts."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from difflib import get_close_matches
from typing import Any, ClassVar

import numpy as np

from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError
from wbc.core.validation import as_float, check_name, known_fields_only

#: ``(low, high, low_inclusive)`` ranges: ``[0, inf]``, that of every numeric field a part's
#: ``RANGES`` does not name, and ``(0, inf]``.
_NON_NEGATIVE = (0.0, None, True)
_POSITIVE = (0.0, None, False)
_Range = tuple[float, float | None, bool]


class _Part:
    """What every part of the configuration does: check its fields where it is built."""

    #: ``(low, high, low_inclusive)`` of the numeric fields whose range is not ``[0, inf]``
    #: (``None``: unbounded); a per-joint-type field's range is that of each of its values.
    RANGES: ClassVar[dict[str, _Range]] = {}
    #: Fields that hold one value per joint type (hip, thigh, calf).
    PER_JOINT_TYPE: ClassVar[tuple[str, ...]] = ()
    __dataclass_fields__: ClassVar[dict[str, Any]]  # every part is a dataclass

    def __post_init__(self) -> None:
        type(self)._check(self)

    @classmethod
    def _check(cls, config: Any) -> None:
        """Check the fields of ``config``, one of this part."""
        for f in fields(cls):
            if f.name in cls.PER_JOINT_TYPE:
                _check_per_joint_type(config, f.name, cls.RANGES[f.name])
            else:
                _in_range(f.name, getattr(config, f.name), cls.RANGES.get(f.name, _NON_NEGATIVE))



@known_fields_only("solver setting")
@dataclass(frozen=True)
class SolverSettings(_Part):
    """Which QP backend solves the tick, the QP's form, and the control period."""

    #: QP backend name (``wbc.backends.available_backends()`` lists them).
    backend: str = "daqp"
    #: Eliminate the floating-base dynamics and the stance contacts (equalities) before the
    #: solve: the same solution from a QP of about 13 variables instead of 31.
    eliminate_dynamics: bool = True
    #: Control period [s]; the controller is meant to run at 1 kHz.
    control_period_s: float = 1e-3

    RANGES: ClassVar[dict[str, _Range]] = {"control_period_s": (1e-4, 0.01, True)}

    @classmethod
    def _check(cls, config: Any) -> None:
        if not isinstance(config.backend, str) or not config.backend:
            raise ConfigurationError(
                f"backend: expected a backend name such as 'daqp' "
                f"(wbc.backends.available_backends() lists the installed ones), "
                f"received {config.backend!r}")
        if not isinstance(config.eliminate_dynamics, bool):
            raise ConfigurationError(f"eliminate_dynamics: expected True or False, "
                                     f"received {config.eliminate_dynamics!r}")
        _in_range("control_period_s", config.control_period_s, cls.RANGES["control_period_s"])


@known_fields_only("task gain")
@dataclass(frozen=True)
class TaskGains(_Part):
    """The tasks' PD gains: ``*_kp`` [1/s^2], damping critical (``2 sqrt(kp)``)."""

    com_kp: float = 150.0
    base_orientation_kp: float = 150.0
    #: Integral gain of the base orientation [1/s^3], on four loaded feet: pulls the base
    #: level against joint friction the model does not know. Off (0) by default: the motor
    #: command's joint PD does that job, and with it the integral made the joints hunt
    #: (stick-slip at 0.01 to 0.08 rad/s) on dry friction.
    base_orientation_ki: float = 0.0
    #: Bound of each component of the orientation error's integral [rad s] (anti-windup).
    base_orientation_integral_limit: float = 0.02
    foot_kp: float = 900.0
    posture_kp: float = 25.0
    #: Damping of a stance foot's residual velocity [1/s] (stops slip).
    contact_damping: float = 10.0


@known_fields_only("cost weight")
@dataclass(frozen=True)
class CostWeights(_Part):
    """The relative weights of the cost's terms: the tasks, the regularisation, the slack."""

    com_weight: float = 20.0
    base_orientation_weight: float = 10.0
    #: A swinging foot's position task.
    foot_weight: float = 30.0
    posture_weight: float = 0.1
    #: Regularisation of the contact forces (pulls them towards an even split).
    force_weight: float = 1e-4
    #: Pull of the accelerations towards the previous tick's (smooth commands).
    acceleration_rate_weight: float = 1e-3
    #: Pull of the contact forces towards the previous tick's (smooth commands).
    force_rate_weight: float = 1e-3
    #: Cost on the change of joint torques from the previous tick [1/(N m)^2]: smooth
    #: commands across contact switches.
    torque_rate_weight: float = 1e-2
    #: Regularisation of the accelerations (keeps the QP strictly convex).
    acceleration_weight: float = 1e-6
    #: Weight of the support-polygon slack (the constraint is soft).
    support_slack_weight: float = 1e3


@known_fields_only("contact setting")
@dataclass(frozen=True)
class ContactSettings(_Part):
    """The contacts: friction, normal-force bounds, the support polygon's barrier."""

    #: Friction coefficient of the contact model (below the floor's, for margin).
    friction_coefficient: float = 0.6
    #: Minimum normal force of a loaded stance foot [N].
    min_normal_force_n: float = 8.0
    #: Maximum normal force of a stance foot [N].
    max_normal_force_n: float = 250.0
    #: Margin of the centre of mass inside the support polygon [m].
    support_margin_m: float = 0.015
    #: Natural frequency of the support-polygon barrier [rad/s].
    support_omega: float = 8.0

    RANGES: ClassVar[dict[str, _Range]] = {
        "friction_coefficient": (0.0, 5.0, False),
        "max_normal_force_n": _POSITIVE,
        "support_omega": _POSITIVE,
    }

    @classmethod
    def _check(cls, config: Any) -> None:
        super()._check(config)
        if config.min_normal_force_n >= config.max_normal_force_n:
            raise ConfigurationError(
                f"min_normal_force_n: expected less than max_normal_force_n "
                f"({config.max_normal_force_n:g} N), received {config.min_normal_force_n:g} N")


@known_fields_only("limit setting")
@dataclass(frozen=True)
class LimitSettings(_Part):
    """How much of the robot's torque the QP may use, and how it keeps to the joint limits."""

    #: Fraction of the URDF effort limits the controller may use (0.9: 10% headroom).
    torque_limit_fraction: float = 0.9
    #: Horizon over which joint position limits become acceleration bounds [s].
    joint_limit_horizon_s: float = 0.05

    RANGES: ClassVar[dict[str, _Range]] = {
        "torque_limit_fraction": (0.0, 1.0, False),
        "joint_limit_horizon_s": _POSITIVE,
    }


@known_fields_only("shaping setting")
@dataclass(frozen=True)
class ShapingSettings(_Part):
    """The motor command (see :class:`wbc.JointReference`): the drivers' PD around the
    desired joint state integrated from the QP's accelerations, on top of the QP's torques;
    and the safe fallback command's damping."""

    #: Position gain of the joints of a stance leg [N m/rad].
    stance_kp: float = 40.0
    #: Velocity gain of the joints of a stance leg [N m s/rad].
    stance_kd: float = 2.0
    #: Position gain of the joints of a swinging leg [N m/rad].
    swing_kp: float = 50.0
    #: Velocity gain of the joints of a swinging leg [N m s/rad].
    swing_kd: float = 2.0
    #: Bound of the desired joint positions' distance from the measured ones [rad].
    reference_position_bound_rad: float = 0.05
    #: Bound of the desired joint velocities' distance from the measured ones [rad/s].
    reference_velocity_bound_rad_s: float = 1.0
    #: Time constant [s] with which a stance leg's desired joint state decays towards the
    #: measured one (0: no decay, only the bounds). Short: three or four legs closed through
    #: the floor must not keep a disagreement (it would push the feet apart and make them slide).
    stance_leak_time_s: float = 0.2
    #: The same for a swinging leg [s]: long, so the PD keeps up with a lagging joint.
    swing_leak_time_s: float = 0.5
    #: Joint damping of the safe fallback command [N m s / rad].
    fallback_damping: float = 2.0
    #: Known viscous friction of the joints (hip, thigh, calf) [N m s/rad], added to the
    #: feed-forward torque along the desired velocity. Zero (the default) compensates none.
    known_joint_damping: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: Known dry friction of the joints (hip, thigh, calf) [N m], added to the feed-forward
    #: torque along the desired velocity. Zero (the default) compensates none.
    known_joint_friction: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: Joint speed [rad/s] over which the dry-friction compensation turns from zero to full
    #: (a tanh: no chatter at rest).
    friction_velocity_scale_rad_s: float = 0.05

    PER_JOINT_TYPE: ClassVar[tuple[str, ...]] = ("known_joint_damping", "known_joint_friction")
    RANGES: ClassVar[dict[str, _Range]] = {
        "stance_kp": (0.0, 500.0, True),
        "stance_kd": (0.0, 50.0, True),
        "swing_kp": (0.0, 500.0, True),
        "swing_kd": (0.0, 50.0, True),
        "known_joint_damping": (0.0, 10.0, True),
        "known_joint_friction": (0.0, 10.0, True),
        "friction_velocity_scale_rad_s": _POSITIVE,
    }


#: The parts in the order of :class:`ControllerConfig`'s fields, with the name each has there.
PARTS: tuple[tuple[str, type[_Part]], ...] = (
    ("solver", SolverSettings), ("gains", TaskGains), ("weights", CostWeights),
    ("contacts", ContactSettings), ("limits", LimitSettings), ("shaping", ShapingSettings))
_PART_TYPES: dict[str, type[_Part]] = dict(PARTS)
#: Every parameter's path, ``part.field`` (``gains.com_kp``), in the parts' order.
PATHS: tuple[str, ...] = tuple(f"{name}.{f.name}" for name, part in PARTS for f in fields(part))
#: The part of each parameter, by its own name (for the edges that still read bare names and
#: for errors that name a parameter's path).
_PART_OF: dict[str, str] = {path.split(".")[1]: path.split(".")[0] for path in PATHS}


@dataclass(frozen=True, init=False)
class ControllerConfig:
    """Parameters of :class:`wbc.WholeBodyController`; defaults are tuned for the GO2.

    One nested shape: a field per part, each the settings of one piece of the controller,
    which takes only its part: :attr:`solver` (:class:`SolverSettings`), :attr:`gains`
    (:class:`TaskGains`), :attr:`weights` (:class:`CostWeights`), :attr:`contacts`
    (:class:`ContactSettings`, the contact schedule's), :attr:`limits`
    (:class:`LimitSettings`) and :attr:`shaping` (:class:`ShapingSettings`, the motor
    command's). A parameter is read and written by its path: ``config.gains.com_kp``;
    ``ControllerConfig(gains=TaskGains(com_kp=200.0))`` or, the others of the part kept at
    their defaults, ``ControllerConfig(gains={"com_kp": 200.0})``;
    ``config.with_values({"gains.com_kp": 200.0})`` (the command line's
    ``--set controller.gains.com_kp=200``). :data:`PATHS` lists every path.

    Raises:
        UnknownNameError: A keyword that is not a part (the message lists the parts, or names
            the path of a parameter given by its bare name: ``com_kp`` is ``gains.com_kp``).
        ConfigurationError: A part of the wrong type, or a value of the wrong type or out of
            its range (the message names the field and its range: the part's ``RANGES``,
            ``[0, inf]`` for the others).
    """

    solver: SolverSettings
    gains: TaskGains
    weights: CostWeights
    contacts: ContactSettings
    limits: LimitSettings
    shaping: ShapingSettings

    def __init__(self, **parts: _Part | Mapping[str, Any]) -> None:
        _check_part_names(parts, "controller parameter")
        for name, part in PARTS:
            object.__setattr__(self, name, _as_part(name, part, parts.get(name)))

    def with_parts(self, **parts: _Part | Mapping[str, Any]) -> ControllerConfig:
        """This config with the parts given replaced: a part, or a mapping of some of its
        fields (the others kept from this config):
        ``config.with_parts(solver={"backend": "osqp"})``.

        Raises:
            UnknownNameError, ConfigurationError: As the constructor.
        """
        _check_part_names(parts, "controller parameter")
        merged: dict[str, Any] = {name: getattr(self, name) for name, _ in PARTS}
        for name, value in parts.items():
            merged[name] = (replace(merged[name], **value) if isinstance(value, Mapping)
                            else value)
        return ControllerConfig(**merged)

    def with_values(self, values: Mapping[str, object]) -> ControllerConfig:
        """This config with the parameters at these paths changed:
        ``config.with_values({"gains.com_kp": 200.0, "solver.backend": "osqp"})``.

        Raises:
            UnknownNameError: Paths that are not parameters (every one named, with the
                nearest path, the valid paths listed).
            ConfigurationError: A value out of its range (the field and the range named).
        """
        unknown = [path for path in values if path not in PATHS]
        if unknown:
            raise UnknownNameError(unknown_paths_message(unknown))
        per_part: dict[str, dict[str, object]] = {}
        for path, value in values.items():
            part, name = path.split(".")
            per_part.setdefault(part, {})[name] = value
        parts: dict[str, _Part] = {}
        for part, changes in per_part.items():
            try:
                parts[part] = replace(getattr(self, part), **changes)
            except ConfigurationError as err:  # named by its path, as it was given
                raise type(err)(f"{part}.{err}") from err
        return self.with_parts(**parts)

    @staticmethod
    def path_of(name: str) -> str:
        """The path (``"gains.com_kp"``) of a parameter given by its bare name (``"com_kp"``),
        for the edges whose files name parameters so (a sweep file's ``gains`` section).

        Raises:
            UnknownNameError: No parameter of that name (the nearest and the valid ones).
        """
        if name not in _PART_OF:
            raise UnknownNameError(
                f"unknown controller parameter {name!r}{_nearest(name, list(_PART_OF))}; "
                f"valid controller parameters: {', '.join(_PART_OF)}")
        return f"{_PART_OF[name]}.{name}"


def unknown_paths_message(unknown: list[str]) -> str:
    """The error for paths that are not the controller's parameters: each named with its
    nearest path (or the path of a bare name), then every valid path."""
    named = "; ".join(f"{path!r}{_nearest(path, PATHS)}" for path in unknown)
    return (f"unknown controller parameter(s) {named}; valid controller parameters: "
            f"{', '.join(PATHS)}")


def _nearest(name: str, valid: Any) -> str:
    """`` (did you mean 'x'?)`` for the closest valid name, the path of a bare name."""
    if name in _PART_OF:
        return f" (it is {_PART_OF[name]}.{name})"
    close = get_close_matches(name, list(valid), n=1, cutoff=0.6)
    bare = [path for path in valid if path.endswith(f".{name.rsplit('.', 1)[-1]}")]
    guess = bare[0] if bare else (close[0] if close else None)
    return f" (did you mean {guess!r}?)" if guess else ""


def _check_part_names(parts: Mapping[str, object], kind: str) -> None:
    """Every key of ``parts`` a part's name (the first other named); a bare parameter name
    gets its path named."""
    for key in parts:
        if key in _PART_OF:
            raise UnknownNameError(
                f"{key}: the controller's parameters are nested; it is "
                f"{_PART_OF[key]}.{key} ({_PART_OF[key]}={{{key!r}: ...}} in Python, "
                f"--set controller.{_PART_OF[key]}.{key}=VALUE on the command line)")
        check_name(kind, key, _PART_TYPES)


def _as_part(name: str, part: type[_Part], value: object) -> _Part:
    """``value`` as the part ``name``: the defaults for None, a part built from a mapping."""
    if value is None:
        return part()
    if isinstance(value, Mapping):
        return part(**value)
    if type(value) is not part:
        raise ConfigurationError(f"{name}: expected a {part.__name__} or a mapping of its "
                                 f"fields, received {type(value).__name__}")
    return value


def _check_per_joint_type(config: Any, name: str, bounds: _Range) -> None:
    value = getattr(config, name)
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 3:
        raise ConfigurationError(
            f"{name}: expected three numbers (hip, thigh, calf), received {value!r}")
    for joint_type, item in zip(("hip", "thigh", "calf"), value):
        _in_range(f"{name} ({joint_type})", item, bounds)
    object.__setattr__(config, name, tuple(float(item) for item in value))


def _in_range(name: str, value: object, bounds: _Range) -> None:
    """Check one number against ``(low, high, low_inclusive)``; every message names the range."""
    low, high, low_inclusive = bounds
    interval = f"{'[' if low_inclusive else '('}{low:g}, {'inf' if high is None else f'{high:g}'}]"
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigurationError(f"{name}: expected a number in {interval}, received {value!r}")
    try:
        as_float(name, value, low=low, high=high, low_inclusive=low_inclusive)
    except NonFiniteError:
        raise NonFiniteError(
            f"{name}: expected a finite number in {interval}, received {value!r}") from None


def config_with_overrides(config: ControllerConfig | None,
                          overrides: Mapping[str, _Part | Mapping[str, Any]]) -> ControllerConfig:
    """``config`` (the defaults when None) with the parts in ``overrides`` changed (a part,
    or a mapping of some of its fields): a controller's keyword arguments.

    Raises:
        ConfigurationError: Keys that are not parts (every one named, the parts listed, a
            bare parameter name with its path), or a value out of its range (the field and
            the range named).
    """
    unknown = sorted(set(overrides) - set(_PART_TYPES))
    if unknown:  # all of them at once
        nested = "; ".join(f"{key} is {_PART_OF[key]}.{key}: {_PART_OF[key]}={{{key!r}: ...}}"
                           for key in unknown if key in _PART_OF)
        raise ConfigurationError(
            f"unknown controller parameter(s) {unknown}; valid controller parameters: "
            f"{', '.join(_PART_TYPES)}" + (f" (they are nested: {nested})" if nested else ""))
    return (config or ControllerConfig()).with_parts(**overrides)
