"""``--set SECTION.FIELD=VALUE``: ``go2-wbc``'s one override form, the settings each command
takes, and the fate of the flags it replaced.

A setting is a path (``estimator.trust_timeout_s``, ``controller.gains.com_kp``,
``run.control_rate_hz``) with its parser; ``--set`` checks the path and the value where it is
read (a usage error naming the path, what was received and what is valid) and puts the value
where the command reads it. Commands share groups of settings (:data:`GROUPS`). Flags that set
one field before ``--set`` existed still work, hidden from ``--help`` (:data:`KEPT_FLAGS`);
the three ``--*-param NAME=VALUE`` flags, which ``--set`` generalises, stop with their
replacement named (:data:`REMOVED_FLAGS`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from difflib import get_close_matches
from typing import Any

from sim.cli.arg_types import (
    estimator_param,
    float_in,
    overlays,
    plant_param,
    sensor_fault,
    sensor_param,
    video_size,
    whole_in,
)
from sim.episode import START_POSES, episode_default
from sim.episode_runner import VIDEO_FPS, VIDEO_SIZE
from sim.plant import Plant
from sim.scene_overlay import DEFAULT_OVERLAYS
from sim.sensor_faults import FAULT_KINDS
from sim.sensor_model import SensorModel
from wbc.controller.controller_config import PATHS, ControllerConfig

#: A push's start [s] (during the hold of a high five) and direction [deg] unless given.
PUSH_AT_S, PUSH_DIR_DEG = 3.5, 90.0


@dataclass(frozen=True)
class Setting:
    """One ``--set`` path: how its value is read and where the command finds it."""

    #: ``section.field`` (``run.control_rate_hz``).
    path: str
    #: The attribute of the parsed arguments it sets (or appends to, with ``append``).
    dest: str
    #: Text to value; raises ``argparse.ArgumentTypeError`` naming what is valid.
    parse: Callable[[str], Any]
    #: What it sets, with its unit and default.
    help: str
    #: The value when not set.
    default: Any = None
    #: The flag that set it before ``--set`` and still does (hidden from ``--help``).
    flag: str = ""
    #: Each ``--set`` adds one (a parameter changed by name, a fault) instead of replacing.
    append: bool = False
    #: The kept flag takes no value (``--viewer-exit``).
    switch: bool = False
    #: For a path ``section.*``: the valid names, found when first needed (the estimators'
    #: are known only by importing them); ``parse`` then reads ``NAME=VALUE``.
    names: Callable[[], tuple[str, ...]] | None = None

    def expanded(self) -> list[Setting]:
        """This setting, or one per name of a ``section.*`` one."""
        if self.names is None:
            return [self]
        section = self.path.removesuffix(".*")
        return [replace(self, path=f"{section}.{name}", parse=_named(self.parse, name),
                        names=None) for name in self.names()]


def _boolean(text: str) -> bool:
    words = {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}
    if text.strip().lower() not in words:
        raise argparse.ArgumentTypeError(f"expected true or false, received {text!r}")
    return words[text.strip().lower()]


def _choice(valid: Iterable[str]) -> Callable[[str], str]:
    valid = tuple(valid)

    def parse(text: str) -> str:
        if text not in valid:
            raise argparse.ArgumentTypeError(
                f"expected one of {', '.join(valid)}, received {text!r}")
        return text

    return parse


def _named(parse_pair: Callable[[str], tuple[str, Any]], name: str) -> Callable[[str], Any]:
    """A parameter's value read by the ``NAME=VALUE`` parser of its kind."""
    return lambda text: parse_pair(f"{name}={text}")


def _controller_value(path: str) -> Callable[[str], tuple[str, Any]]:
    """A controller parameter's value, typed as its default. Its range is checked with the
    others given (``contacts.min_normal_force_n`` below ``max_normal_force_n``) where the
    command builds the configuration (:attr:`sim.episode.Episode.controller_config`)."""
    default = getattr(getattr(ControllerConfig(), path.split(".")[0]), path.split(".")[1])

    def parse(text: str) -> tuple[str, Any]:
        value: Any = text
        if isinstance(default, bool):
            value = _boolean(text)
        elif isinstance(default, tuple):
            value = tuple(_number(part) for part in text.split(","))
        elif isinstance(default, float):
            value = _number(text)
        return path, value

    return parse


def _number(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text  # the part's check says what it expected


def _controller() -> list[Setting]:
    defaults = ControllerConfig()
    return [Setting(f"controller.{path}", "controller_param", _controller_value(path),
                    f"the controller's {path.split('.')[1]} (default: "
                    f"{getattr(getattr(defaults, path.split('.')[0]), path.split('.')[1])})",
                    append=True)
            for path in PATHS if path != "solver.control_period_s"]


def _estimator_names() -> tuple[str, ...]:
    """Every estimator's parameters (imports them: not while the parser is built)."""
    from wbc.estimation.estimator_config import EstimatorConfig
    from wbc.estimation.invariant_ekf import InvariantEkfConfig

    return tuple(dict.fromkeys((*InvariantEkfConfig.field_names(),
                                *EstimatorConfig.field_names())))


def _estimator() -> list[Setting]:
    return [Setting("estimator.*", "estimator_param", estimator_param,
                    "a state estimator parameter (default: the estimator's value; the "
                    "chosen estimator checks it)", append=True, names=_estimator_names)]


def _sensors() -> list[Setting]:
    return [Setting(f"sensors.{name}", "sensor_param", _named(sensor_param, name),
                    "a sensor model parameter (default: the --sensors preset's)", append=True)
            for name in SensorModel.parameter_names()]


def _plant() -> list[Setting]:
    return [Setting(f"plant.{name}", "plant_param", _named(plant_param, name),
                    "a simulated plant parameter (default: the --plant preset's)", append=True)
            for name in Plant.parameter_names()]


def _rates() -> list[Setting]:
    rate = 1.0 / episode_default("control_period_s")
    return [
        Setting("run.control_rate_hz", "control_rate",
                float_in(10.0, 10000.0, what="a rate", unit="Hz", fmt="g"),
                f"control rate [Hz] (default: {rate:g}; the GO2's usual is 500)",
                default=rate, flag="--control-rate"),
        Setting("run.physics_dt_s", "physics_dt",
                float_in(1e-5, 0.01, what="a timestep", unit="s", fmt="g"),
                "physics timestep [s]; a whole number of them per control period "
                "(default: 0.001, or the control period if shorter)",
                default=episode_default("physics_timestep_s"), flag="--physics-dt")]


def _state() -> list[Setting]:
    delay, seed = episode_default("command_delay_s"), episode_default("sensor_seed")
    return [
        Setting("run.command_delay_s", "command_delay",
                float_in(0.0, 0.1, what="a delay", unit="s", fmt="g"),
                "time [s] between a command and the motor drivers applying it, a whole number "
                f"of control periods (default: {delay:g}; legged_control simulates a Unitree "
                "robot with 0.009)", default=delay, flag="--command-delay"),
        Setting("run.calibrate_s", "calibrate",
                float_in(0.2, 60.0, what="a duration", unit="s", fmt="g"),
                "before the goal, stand this long [s] (2 is enough) with the centre of mass "
                "circling 4.5 cm: learn each foot sensor's offset and gain and check the IMU "
                "at rest (default: no calibration)",
                default=episode_default("calibrate_s") or None, flag="--calibrate"),
        Setting("sensors.seed", "sensor_seed", whole_in(0, 2**31 - 1, what="a seed"),
                f"seed of the sensors' noise and biases (default: {seed})", default=seed,
                flag="--sensor-seed"),
        Setting("sensors.fault", "sensor_fault", sensor_fault,
                "a sensor fault KIND,AT_S,DURATION_S[,NAME] from sim time AT_S for "
                f"DURATION_S, repeatable; KIND: {', '.join(FAULT_KINDS)}; NAME: the foot of a "
                "foot fault (default FR) or the joint of joint_nan (default FR_thigh_joint) "
                "(default: none)", default=[], flag="--sensor-fault", append=True)]


def _run() -> list[Setting]:
    return [
        Setting("run.start_pose", "start_pose", _choice(START_POSES),
                f"pose the robot starts in: {', '.join(START_POSES)} (default: lying for "
                "'stand', standing otherwise)", flag="--start-pose"),
        Setting("run.viewer_exit", "viewer_exit", _boolean,
                "with --viewer: close the window when the goal ends (default: false, the "
                "window stays open on the final state until you close it)", default=False,
                flag="--viewer-exit", switch=True),
        Setting("push.at_s", "push_at", float_in(0.0, 3600.0, what="a sim time", unit="s",
                                                 fmt="g"),
                f"simulated time [s] the --push starts (default: {PUSH_AT_S:g}, during the "
                "hold of a high five)", flag="--push-at"),
        Setting("push.dir_deg", "push_dir", float_in(-360.0, 360.0, what="an angle",
                                                     unit="deg", fmt="g"),
                "the --push's direction [deg] relative to the robot's heading: 0 forward, "
                f"90 left, 180 backward, 270 right (default: {PUSH_DIR_DEG:g})",
                flag="--push-dir")]


def _video() -> list[Setting]:
    width, height = VIDEO_SIZE
    return [
        Setting("video.fps", "fps", whole_in(1, 240, what="frames per second"),
                f"video frame rate [1/s] of simulated time (default: {VIDEO_FPS})",
                flag="--fps"),
        Setting("video.size", "video_size", video_size,
                f"video frame size in pixels, WxH (default: {width}x{height})",
                flag="--video-size"),
        Setting("video.overlay", "overlay", overlays,
                "what the viewer and the video draw over the robot, comma-separated: com, "
                "polygon, forces, measured, target; or all, or none (default: "
                f"{','.join(DEFAULT_OVERLAYS)})", flag="--overlay")]


#: The groups of settings, by name; a command takes the groups it needs.
GROUPS: dict[str, Callable[[], list[Setting]]] = {
    "controller": _controller, "estimator": _estimator, "sensors": _sensors, "plant": _plant,
    "rates": _rates, "state": _state, "run": _run, "video": _video}
#: Every group: the goal commands' (high-five, stand, sit, trajectory).
GOAL_GROUPS = tuple(GROUPS)

#: The flags ``--set`` replaced and that now stop, by the group that replaced them.
REMOVED_FLAGS = {"plant": ("--plant-param", "plant"), "sensors": ("--sensor-param", "sensors"),
                 "estimator": ("--estimator-param", "estimator")}


def kept_flags() -> dict[str, str]:
    """Every flag that still works, hidden from ``--help``, and the path it sets."""
    return {s.flag: s.path for make in GROUPS.values() for s in make() if s.flag}


class _RemovedFlag(argparse.Action):
    """An old flag: a usage error naming its replacement."""

    def __init__(self, option_strings: list[str], dest: str, *, section: str,
                 **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs="?", help=argparse.SUPPRESS, **kwargs)
        self.section = section

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        parser.error(f"{option_string} was replaced by --set {self.section}.<field>=<value>"
                     f" (e.g. --set {self.section}.{_example(self.section)}; "
                     f"--set help lists them)")


def _example(section: str) -> str:
    return {"plant": "calf_friction_loss=1.4", "sensors": "gyro_noise_rad_s=0.01",
            "estimator": "use_foot_force=false"}[section]


class _SetAction(argparse.Action):
    """``--set SECTION.FIELD=VALUE``, repeatable: checked and applied where it is read."""

    def __init__(self, option_strings: list[str], dest: str, *, settings: dict[str, Setting],
                 refused: dict[str, str], **kwargs: Any) -> None:
        super().__init__(option_strings, dest, default=[], **kwargs)
        self.settings, self.refused = settings, refused

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        text = str(values)
        if text in ("help", "list"):
            print(listing(self.settings.values()), end="")
            parser.exit(0)
        path, sep, value_text = text.partition("=")
        if not sep or "." not in path:
            parser.error(f"--set: expected SECTION.FIELD=VALUE (e.g. "
                         f"{_examples(self.settings).split(', ')[0]}), received {text!r}")
        if path in self.refused:
            parser.error(f"--set {path}: {self.refused[path]}")
        setting = self.settings.get(path) or _by_name(self.settings, path)
        if setting is None:
            parser.error(unknown_setting(text, self.settings))
        try:
            value = setting.parse(value_text)
        except argparse.ArgumentTypeError as err:
            field = path.split(".", 1)[1]
            detail = str(err).removeprefix(f"{field}: ").removeprefix(
                f"{field.rsplit('.', 1)[-1]}: ")
            parser.error(f"--set {path}: {detail}")
        if setting.append:
            value = [*(getattr(namespace, setting.dest, None) or []), value]
        setattr(namespace, setting.dest, value)
        setattr(namespace, self.dest, [*(getattr(namespace, self.dest, None) or []), path])
        set_by = dict(getattr(namespace, "set_by", None) or {})
        set_by[setting.dest] = path
        namespace.set_by = set_by


def _by_name(settings: dict[str, Setting], path: str) -> Setting | None:
    """The setting of ``path`` under a ``section.*`` one, if its name is valid."""
    wildcard = settings.get(f"{path.split('.')[0]}.*")
    if wildcard is None:
        return None
    return next((s for s in wildcard.expanded() if s.path == path), None)


def unknown_setting(text: str, settings: dict[str, Setting]) -> str:
    """The usage error for ``PATH=VALUE`` whose path no setting has: the nearest, then the
    valid ones."""
    path = text.partition("=")[0]
    section = path.split(".")[0]
    settings = {s.path: s for setting in settings.values() for s in setting.expanded()}
    close = get_close_matches(path, list(settings), n=1, cutoff=0.6)
    guess = f" (did you mean {close[0]!r}?)" if close else ""
    in_section = [p for p in settings if p.startswith(f"{section}.")]
    if in_section:
        return (f"--set: unknown setting {path!r} in {text!r}{guess}; valid {section} settings: "
                f"{', '.join(in_section)}")
    sections = list(dict.fromkeys(p.split(".")[0] for p in settings))
    return (f"--set: unknown section {section!r} in {text!r}{guess}; valid sections: "
            f"{', '.join(sections)} (--set help lists every setting)")


def listing(settings: Iterable[Setting]) -> str:
    """Every setting's path and help, one a line: what ``--set help`` prints."""
    lines = [f"  {s.path:<44} {s.help}" for setting in settings for s in setting.expanded()]
    return "settings (--set SECTION.FIELD=VALUE, repeatable):\n" + "\n".join(lines) + "\n"


def add_settings(parser: argparse.ArgumentParser, group: Any, groups: Iterable[str], *,
                 refused: dict[str, str] | None = None) -> dict[str, Setting]:
    """``--set`` on ``group`` with the settings of ``groups`` (:data:`GROUPS`' names), their
    defaults on ``parser``, the kept flags hidden and the removed ones refusing.

    Args:
        refused: Paths this command refuses, with the reason (what sets it instead).
    """
    groups = tuple(groups)
    settings = {s.path: s for name in groups for s in GROUPS[name]()}
    refused = {"controller.solver.control_period_s": "set by the control rate "
               "(--set run.control_rate_hz=HZ)", **(refused or {})}
    sections = ", ".join(dict.fromkeys(p.split(".")[0] for p in settings))
    group.add_argument(
        "--set", action=_SetAction, settings=settings, refused=refused, dest="settings",
        metavar="SECTION.FIELD=VALUE",
        help=f"change one setting, repeatable; sections: {sections} (e.g. "
             f"{_examples(settings)}); '--set help' lists every setting with its default "
             "(default: the presets' values)")
    parser.set_defaults(set_by={}, **{s.dest: [] for s in settings.values() if s.append})
    for setting in settings.values():
        if setting.flag:
            _add_kept_flag(group, setting)
    for name in groups:
        if name in REMOVED_FLAGS:
            flag, section = REMOVED_FLAGS[name]
            group.add_argument(flag, action=_RemovedFlag, section=section,
                               dest=f"removed_{section}")
    return settings


def _examples(settings: dict[str, Setting]) -> str:
    wanted = ("estimator.trust_timeout_s=0.05", "controller.gains.com_kp=200",
              "sensors.gyro_noise_rad_s=0.01", "run.control_rate_hz=500")
    sections = {path.split(".")[0] for path in settings}
    return ", ".join(w for w in wanted if w.split(".")[0] in sections)


def _add_kept_flag(group: Any, setting: Setting) -> None:
    """An old flag that sets one setting, as before, hidden from ``--help``."""
    if setting.switch:
        group.add_argument(setting.flag, dest=setting.dest, action="store_true",
                           help=argparse.SUPPRESS)
        return
    group.add_argument(setting.flag, dest=setting.dest, type=setting.parse,
                       action="append" if setting.append else "store",
                       default=[] if setting.append else setting.default,
                       help=argparse.SUPPRESS)
