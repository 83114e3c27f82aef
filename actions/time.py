"""rclpy-style Time: ``Time(seconds=..., nanoseconds=...)`` with ``.to_msg()``, as ``rclpy.time``.

A point on the robot's clock, which here is the simulated one (``ControlLoop.robot.time_s``),
so there is no clock type. Not the message: :class:`actions.messages.Time`
(``builtin_interfaces/Time``) is what ``header.stamp`` holds, and :meth:`Time.to_msg` builds
one::

    from actions.time import Time                # rclpy: from rclpy.time import Time

    goal.trajectory.header.stamp = Time(seconds=loop.robot.time_s + 1.0).to_msg()

``Time - Time`` is a :class:`~actions.duration.Duration`; ``Time +/- Duration`` is a ``Time``.
"""

from __future__ import annotations

import functools

from actions import messages
from actions.duration import Duration, total_nanoseconds
from wbc.core.errors import ConfigurationError

_NANOSECONDS_PER_SECOND = 1_000_000_000


@functools.total_ordering
class Time:
    """A point in time in nanoseconds since the clock's start, as ``rclpy.time.Time``.

    Args:
        seconds: Seconds [s] since the clock's start.
        nanoseconds: Nanoseconds [ns] added to ``seconds``, an integer.

    Raises:
        ConfigurationError: An argument has the wrong type, is not finite, or the time is
            negative.
    """

    __slots__ = ("_nanoseconds",)

    def __init__(self, *, seconds: float = 0, nanoseconds: int = 0) -> None:
        total = total_nanoseconds("Time", seconds, nanoseconds)
        if total < 0:
            raise ConfigurationError(
                f"Time must not be negative; received seconds={seconds!r}, "
                f"nanoseconds={nanoseconds!r} ({total} ns in all)"
            )
        self._nanoseconds = total

    @property
    def nanoseconds(self) -> int:
        """The time in whole nanoseconds [ns] since the clock's start."""
        return self._nanoseconds

    def seconds_nanoseconds(self) -> tuple[int, int]:
        """``(seconds, nanoseconds)``: whole seconds and the nanoseconds beyond them."""
        sec, nanosec = divmod(self._nanoseconds, _NANOSECONDS_PER_SECOND)
        return sec, nanosec

    def to_msg(self) -> messages.Time:
        """The ``builtin_interfaces/Time`` message, e.g. for ``header.stamp``."""
        sec, nanosec = self.seconds_nanoseconds()
        return messages.Time(sec=sec, nanosec=nanosec)

    @classmethod
    def from_msg(cls, msg: messages.Time) -> Time:
        """The time a ``Time`` message holds.

        Raises:
            ConfigurationError: ``msg`` is not a :class:`actions.messages.Time`.
        """
        if not isinstance(msg, messages.Time):
            raise ConfigurationError(
                f"Time.from_msg needs an actions.messages.Time; received {msg!r} "
                f"(type {type(msg).__name__})"
            )
        return cls(seconds=msg.sec, nanoseconds=msg.nanosec)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Time):
            return NotImplemented
        return self._nanoseconds == other._nanoseconds

    def __lt__(self, other: Time) -> bool:
        if not isinstance(other, Time):
            return NotImplemented
        return self._nanoseconds < other._nanoseconds

    def __hash__(self) -> int:
        return hash(self._nanoseconds)

    def __add__(self, other: Duration) -> Time:
        if not isinstance(other, Duration):
            return NotImplemented
        return Time(nanoseconds=self._nanoseconds + other.nanoseconds)

    __radd__ = __add__

    def __sub__(self, other: Time | Duration) -> Time | Duration:
        if isinstance(other, Time):
            return Duration(nanoseconds=self._nanoseconds - other._nanoseconds)
        if isinstance(other, Duration):
            return Time(nanoseconds=self._nanoseconds - other.nanoseconds)
        return NotImplemented

    def __repr__(self) -> str:
        return f"Time(nanoseconds={self._nanoseconds})"
