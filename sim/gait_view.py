"""What a walking motion shows the viewer, the video and the plot: a plain-data :class:`GaitView`.

Any motion that has the four attributes of :class:`GaitSource` (``wbc.locomotion.Walking``
has them) can be drawn: which legs swing, where they will land, the commanded and the
measured velocity. The view is taken once a frame from the source and the controller's
state; nothing here imports MuJoCo or the motion's module.

Velocities are in the *heading frame*: ``forward`` along the base's heading (its yaw),
``lateral`` to its left, both horizontal [m/s], and the yaw rate about the world's vertical
[rad/s]. :func:`heading_velocities` computes them from Pinocchio's ``(q, v)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol, cast, runtime_checkable

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import LEGS

if TYPE_CHECKING:
    from actions.robot.robot_loop import RobotLoop

#: The three commanded or measured components, their units and their order.
VELOCITY_NAMES: tuple[str, ...] = ("forward", "lateral", "yaw rate")
VELOCITY_UNITS: tuple[str, ...] = ("m/s", "m/s", "rad/s")


@runtime_checkable
class GaitSource(Protocol):
    """What a motion that walks exposes for the overlays (``wbc.locomotion.Walking`` does).

    Attributes:
        swing_legs: The legs in swing now (the others stand).
        footholds: The planned touch-down point [m] (world) of each swing leg.
        commanded_velocity: (3,) forward, lateral [m/s], yaw rate [rad/s] asked for.
        measured_velocity: (3,) the same, as the controller's state measures it.
    """

    swing_legs: tuple[str, ...]
    footholds: Mapping[str, np.ndarray]
    commanded_velocity: np.ndarray
    measured_velocity: np.ndarray


def heading_rad(q: np.ndarray) -> float:
    """The base's yaw [rad] for a configuration ``q`` (quaternion ``q[3:7]`` as x, y, z, w)."""
    x, y, z, w = (float(c) for c in q[3:7])
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def heading_velocities(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Forward, lateral [m/s] and yaw rate [rad/s] in the heading frame, per row.

    Args:
        q: (N, 19) or (19,) configurations (Pinocchio: base position, quaternion x y z w).
        v: (N, 18) or (18,) velocities (Pinocchio: linear and angular in the base frame).

    Returns:
        (N, 3) or (3,): the base's world velocity turned by minus its yaw (so a tilted base
        walking straight ahead reads as forward), and its world angular velocity's vertical
        component.
    """
    q2, v2 = np.atleast_2d(q), np.atleast_2d(v)
    if q2.shape[1] != 19 or v2.shape[1] != 18 or len(q2) != len(v2):
        raise ConfigurationError(
            f"q, v: expected (N, 19) and (N, 18) arrays of as many rows, received shapes "
            f"{np.shape(q)} and {np.shape(v)}")
    x, y, z, w = (q2[:, 3 + i] for i in range(4))
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    # The rotation's rows 0, 1 (world x, y of the base axes) and row 2 (world z).
    r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    r10, r11, r12 = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    r20, r21, r22 = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
    lin, ang = v2[:, :3], v2[:, 3:6]
    vx = r00 * lin[:, 0] + r01 * lin[:, 1] + r02 * lin[:, 2]
    vy = r10 * lin[:, 0] + r11 * lin[:, 1] + r12 * lin[:, 2]
    yaw = np.arctan2(r10, r00)
    cos, sin = np.cos(yaw), np.sin(yaw)
    out = np.column_stack([cos * vx + sin * vy, -sin * vx + cos * vy,
                           r20 * ang[:, 0] + r21 * ang[:, 1] + r22 * ang[:, 2]])
    return out if np.ndim(q) == 2 else out[0]


@dataclass(frozen=True)
class GaitView:
    """The walking state one frame draws: plain data, checked when built.

    Attributes:
        swing_legs: Legs in swing, in ``LEGS`` order (the others are in stance).
        feet: (4, 3) foot centres [m] (world), rows in ``LEGS`` order.
        footholds: Planned touch-down point [m] (world) per swing leg that has one.
        base_position: (3,) the base's origin [m] (world).
        heading_rad: The base's yaw [rad].
        commanded: (3,) commanded forward, lateral [m/s] and yaw rate [rad/s].
        measured: (3,) measured forward, lateral [m/s] and yaw rate [rad/s].
    """

    swing_legs: tuple[str, ...]
    feet: np.ndarray
    footholds: Mapping[str, np.ndarray]
    base_position: np.ndarray
    heading_rad: float
    commanded: np.ndarray
    measured: np.ndarray
    stance_legs: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        swing = tuple(self.swing_legs)
        for leg in swing:
            check_name("swing leg", leg, LEGS)
        feet = np.array(self.feet, dtype=float)
        if feet.shape != (len(LEGS), 3) or not np.isfinite(feet).all():
            raise ConfigurationError(
                f"feet: expected a finite (4, 3) array (rows {', '.join(LEGS)}), received "
                f"shape {feet.shape}")
        footholds = {}
        for leg, point in self.footholds.items():
            check_name("foothold leg", leg, LEGS)
            footholds[leg] = as_vector(f"footholds[{leg}]", point, 3)
        heading = float(self.heading_rad)
        if not math.isfinite(heading):
            raise ConfigurationError(f"heading_rad: expected a finite angle, received {heading}")
        values = {"swing_legs": tuple(leg for leg in LEGS if leg in swing), "feet": feet,
                  "footholds": footholds, "heading_rad": heading,
                  "base_position": as_vector("base_position", self.base_position, 3),
                  "commanded": as_vector("commanded", self.commanded, 3),
                  "measured": as_vector("measured", self.measured, 3),
                  "stance_legs": tuple(leg for leg in LEGS if leg not in swing)}
        for name, value in values.items():  # frozen: set once, here
            object.__setattr__(self, name, value)

    @classmethod
    def of(cls, source: GaitSource, *, q: np.ndarray, feet: np.ndarray) -> GaitView:
        """The view of ``source`` at the controller's state ``q`` (19,) and ``feet`` (4, 3) [m].

        Raises:
            ConfigurationError: ``source`` lacks an attribute of :class:`GaitSource`, or one
                of its values is malformed (the message names it).
        """
        if not isinstance(source, GaitSource):
            missing = [name for name in ("swing_legs", "footholds", "commanded_velocity",
                                         "measured_velocity") if not hasattr(source, name)]
            raise ConfigurationError(
                f"source: expected a motion with swing_legs, footholds, commanded_velocity "
                f"and measured_velocity; {type(source).__name__} lacks {', '.join(missing)}")
        return cls(swing_legs=tuple(source.swing_legs), feet=feet,
                   footholds=dict(source.footholds), base_position=np.asarray(q[:3]),
                   heading_rad=heading_rad(q), commanded=source.commanded_velocity,
                   measured=source.measured_velocity)

    def world_velocity(self, which: str) -> np.ndarray:
        """``commanded`` or ``measured`` horizontal velocity as a world vector (3,) [m/s]."""
        check_name("velocity", which, ("commanded", "measured"))
        forward, lateral, _ = self.commanded if which == "commanded" else self.measured
        cos, sin = math.cos(self.heading_rad), math.sin(self.heading_rad)
        return np.array([cos * forward - sin * lateral, sin * forward + cos * lateral, 0.0])


@runtime_checkable
class WalkingBehaviour(Protocol):
    """A behaviour that drives a walking motion
    (:class:`actions.go2.walk_behaviour.WalkBehaviour`): ``walking`` is the motion, ``None``
    before it starts."""

    walking: object | None


#: Whether a type's instances conform to a protocol, by (type, protocol): an ``isinstance``
#: against a runtime-checkable protocol costs about 10 us (Python 3.11), once a tick here.
_CONFORMS: dict[tuple[type, type], bool] = {}


def _conforms(value: object, protocol: type) -> bool:
    """``isinstance(value, protocol)``, remembered per type of ``value`` (the protocols here
    name attributes every instance of a class sets in its constructor)."""
    key = (type(value), protocol)
    known = _CONFORMS.get(key)
    if known is None:
        known = _CONFORMS[key] = isinstance(value, protocol)
    return known


def walking_motion(loop: RobotLoop) -> GaitSource | None:
    """The walking motion of the goal ``loop``'s actions run now (a Walk goal, or the
    ``cmd_vel`` stream's), ``None`` when nothing walks."""
    for record in loop.runner.active_goals()[:1]:  # the goal executing, if any
        behaviour = record.behaviour
        if _conforms(behaviour, WalkingBehaviour):
            motion = cast(WalkingBehaviour, behaviour).walking
            if motion is not None and _conforms(motion, GaitSource):
                return cast(GaitSource, motion)
    return None
