"""What the options of ``go2-wbc`` take: argparse types that check a value and say what is valid."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

from actions.ros_interfaces.control_msgs import FollowJointTrajectoryGoal
from sim.cli.trajectory_file import load_trajectory_goal
from sim.plant import Plant
from sim.scene_overlay import parse_overlays
from sim.sensor_faults import FAULT_KINDS, SensorFault
from sim.sensor_model import SensorModel
from wbc.core.errors import ConfigurationError, WbcError


def _number(text: str, expected: str) -> float:
    """``text`` as a finite number; else a usage error saying what was ``expected``."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return value


def float_in(low: float, high: float, *, what: str, unit: str, fmt: str = ".2f"
             ) -> Callable[[str], float]:
    """An argparse type: a finite number in ``[low, high]``; the message says the range."""
    expected = f"{what} in [{low:{fmt}}, {high:{fmt}}] {unit}".rstrip()

    def parse(text: str) -> float:
        value = _number(text, expected)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text}")
        return value

    return parse


def whole_in(low: int, high: int, *, what: str, note: str = "") -> Callable[[str], int]:
    """An argparse type: an integer in ``[low, high]`` (``note``: said after the range)."""
    expected = f"{what} in [{low}, {high}]" + (f" ({note})" if note else "")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {expected}, received {text}")
        return value

    return parse


def push(text: str) -> tuple[float, float]:
    """``FORCE_N,DURATION_S`` as ``(force [N], duration [s])``; the push is built with its time
    and direction, once all the options are known."""
    expected = "FORCE_N,DURATION_S with a force in [0, 500] N and a duration in (0, 5] s"
    parts = text.split(",")
    try:
        force, duration = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected {expected} (e.g. 40,0.1), received {text!r}") from None
    if not (0.0 <= force <= 500.0 and 0.0 < duration <= 5.0):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return force, duration


def video_size(text: str) -> tuple[int, int]:
    """``WxH``: a video's ``(width, height)`` in pixels, both even."""
    expected = "WIDTHxHEIGHT in pixels, both even and in [16, 3840] (e.g. 640x480)"
    try:
        width, height = (int(p) for p in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
    if not all(16 <= n <= 3840 and n % 2 == 0 for n in (width, height)):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    return width, height


def overlays(text: str) -> tuple[str, ...]:
    """A comma-separated list of overlays, ``all`` or ``none`` (:func:`parse_overlays`)."""
    try:
        return parse_overlays(text)
    except ConfigurationError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def output_file(*suffixes: str) -> Callable[[str], Path]:
    """An argparse type: a file path with one of ``suffixes`` in an existing directory."""
    def parse(text: str) -> Path:
        path = Path(text)
        if path.suffix.lower() not in suffixes:
            raise argparse.ArgumentTypeError(
                f"expected a file name ending in {' or '.join(suffixes)}, received {text!r}")
        if not path.parent.is_dir():
            raise argparse.ArgumentTypeError(
                f"directory {str(path.parent)!r} does not exist (for {text!r})")
        return path

    return parse


def trajectory_file(text: str) -> FollowJointTrajectoryGoal:
    """A trajectory file's path: the FollowJointTrajectory goal it holds."""
    try:
        return load_trajectory_goal(Path(text))
    except OSError as err:
        raise argparse.ArgumentTypeError(
            f"cannot read {text!r}: {err.strerror or err}") from None
    except (ValueError, ConfigurationError) as err:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not a valid trajectory file: {err}") from None


def plant_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of a plant parameter, checked by the plant itself (name and range).

    The value is a number, three comma-separated numbers for ``payload_offset_m`` or a word
    for ``cone``; anything else is handed over as text, so that the plant's message says
    what it expected.
    """
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    value: Any = value_text
    if name != "cone":
        parts = tuple(_number_or_text(v) for v in value_text.split(","))
        value = parts if len(parts) > 1 else parts[0]
        if name == "condim" and isinstance(value, float) and value.is_integer():
            value = int(value)
    try:
        # The ranges do not depend on the preset, so any plant checks them.
        Plant().with_params(**{name: value})
    except WbcError as err:
        message = str(err)
        if name.startswith("joint_"):  # reported for the first joint type: name the option's
            message = f"{name}:{message.partition(':')[2]}"
        raise argparse.ArgumentTypeError(message) from None
    return name, value


def sensor_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of a sensor-model parameter, checked by the model (name and range)."""
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    value: Any = _number_or_text(value_text)
    if name == "foot_force_integer":
        words = {"true": True, "1": True, "yes": True, "false": False, "0": False, "no": False}
        value = words.get(value_text.strip().lower(), value_text)
    try:
        SensorModel().with_params(**{name: value})
    except WbcError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return name, value


def estimator_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of an estimator parameter; checked once the estimator is known."""
    name, sep, value_text = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, received {text!r}")
    words = {"true": True, "yes": True, "false": False, "no": False}
    value: Any = words.get(value_text.strip().lower(), _number_or_text(value_text))
    if "," in value_text:  # one number per foot (FL,FR,RL,RR)
        value = tuple(_number_or_text(part) for part in value_text.split(","))
    return name, value


def sensor_fault(text: str) -> SensorFault:
    """``KIND,AT_S,DURATION_S[,NAME]``: a sensor fault on the simulated clock."""
    parts = [p.strip() for p in text.split(",")]
    expected = (f"KIND,AT_S,DURATION_S[,FOOT_OR_JOINT] with KIND one of "
                f"{', '.join(FAULT_KINDS)} (e.g. dropout,3.5,0.02 or foot_zero,1,5,RL)")
    if len(parts) not in (3, 4):
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}")
    try:
        at_s, duration_s = float(parts[1]), float(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {expected}, received {text!r}") from None
    try:
        return SensorFault(parts[0], at_s, duration_s, parts[3] if len(parts) == 4 else "")
    except WbcError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def _number_or_text(text: str) -> float | str:
    try:
        return float(text)
    except ValueError:
        return text
