"""Disturbances for robustness runs: command delay, pushes (plants: :mod:`sim.plant`; sensors:
:mod:`sim.sensors`, :mod:`sim.sensor_faults`).

Everything is seeded and happens in simulated time, so a run with the same settings and
seed is the same run.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from actions.robot.robot_interface import RobotInterface, RobotWrapper
from wbc.core.errors import ConfigurationError
from wbc.robot_io.motor_command import MotorCommand


class DelayedRobot(RobotWrapper):
    """A robot whose commands arrive ``delay_ticks`` control periods late.

    Wraps a :class:`~actions.robot.robot_interface.RobotInterface` (same orders; sensors and the
    exact state pass through): a transport delay between the controller and the motor
    drivers (legged_control's simulation of a Unitree robot applies commands 9 ms late).
    Until the queue fills, the first command is applied. Sensor noise is the sensor model's
    (:class:`sim.sensors.SensorModel`).

    Args:
        robot: The robot.
        delay_ticks: Control periods between a command and its application, in [0, 100].
    """

    def __init__(self, robot: RobotInterface, delay_ticks: int):
        if isinstance(delay_ticks, bool) or not isinstance(delay_ticks, int) or not (
                0 <= delay_ticks <= 100):
            raise ConfigurationError(
                f"delay_ticks: expected a whole number in [0, 100], received {delay_ticks!r}")
        super().__init__(robot)
        self.delay_ticks = delay_ticks
        self._queue: deque[MotorCommand] = deque()

    def write_command(self, command: MotorCommand) -> None:
        """Queue a command; the one from ``delay_ticks`` periods ago is applied."""
        self._queue.append(command.copy())
        if len(self._queue) <= self.delay_ticks:
            self.robot.write_command(self._queue[0])  # the first command, until the queue fills
            return
        self.robot.write_command(self._queue.popleft())


@dataclass(frozen=True)
class Push:
    """A force on a body for a while, starting at a simulated time.

    Attributes:
        at_s: Start time [s]. force_n: Magnitude [N]. duration_s: Duration [s].
        direction_deg: Direction in the horizontal plane (0 forward, 90 left, 270 right).
        body: The body pushed (``base``, or ``FR_foot`` for a hand on the raised foot).
        vertical_n: A vertical component [N] (positive up).
        relative_to_heading: Whether ``direction_deg`` is relative to the base's heading
            (yaw) when the push starts, rather than to the world's x axis.
    """

    at_s: float
    force_n: float
    duration_s: float
    direction_deg: float = 0.0
    body: str = "base"
    vertical_n: float = 0.0
    relative_to_heading: bool = False

    @property
    def impulse_ns(self) -> float:
        """Horizontal impulse [N s]."""
        return self.force_n * self.duration_s

    def vector(self, heading_rad: float = 0.0) -> np.ndarray:
        """World force [N], for a base heading ``heading_rad`` [rad] when relative to it."""
        angle = math.radians(self.direction_deg)
        if self.relative_to_heading:
            angle = heading_rad + angle
        return np.array([self.force_n * math.cos(angle), self.force_n * math.sin(angle),
                         self.vertical_n])


class PushSchedule:
    """Applies pushes at their times: add it to a :class:`sim.control_loop.ControlLoop`'s hooks.

    Example:
        >>> loop.hooks.append(PushSchedule(loop.sim, [Push(at_s=4.0, force_n=30, duration_s=0.1)]))
    """

    def __init__(self, sim, pushes: list[Push]):
        self.sim = sim
        self.pending = sorted(pushes, key=lambda p: p.at_s)
        #: ``(time [s], push, world force [N])`` of each push applied.
        self.applied: list[tuple[float, Push, np.ndarray]] = []

    def __call__(self, loop, out) -> None:
        now = self.sim.time_s
        while self.pending and self.pending[0].at_s <= now + 1e-9:
            push = self.pending.pop(0)
            force = push.vector(self._heading_rad())
            self.sim.apply_force(force, push.duration_s, body=push.body)
            self.applied.append((now, push, force))

    def _heading_rad(self) -> float:
        """The base's yaw [rad] now."""
        x, y, z, w = self.sim.state()[0][3:7]  # Pinocchio's (x, y, z, w)
        return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
