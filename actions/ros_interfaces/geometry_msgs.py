"""``geometry_msgs``: vectors, rotations, transforms, twists (parts of multi-DOF trajectories)."""

from __future__ import annotations

from dataclasses import dataclass, field

from actions.messages import Message


@dataclass(slots=True)
class Vector3(Message):
    """``geometry_msgs/Vector3``."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0


@dataclass(slots=True)
class Quaternion(Message):
    """``geometry_msgs/Quaternion``, ``(x, y, z, w)``; the default is the identity."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    w: float = 1.0


@dataclass(slots=True)
class Transform(Message):
    """``geometry_msgs/Transform``: translation [m] and rotation."""

    translation: Vector3 = field(default_factory=Vector3)
    rotation: Quaternion = field(default_factory=Quaternion)


@dataclass(slots=True)
class Twist(Message):
    """``geometry_msgs/Twist``: linear [m/s] and angular [rad/s] velocity."""

    linear: Vector3 = field(default_factory=Vector3)
    angular: Vector3 = field(default_factory=Vector3)
