"""rclpy-style Duration: ``Duration(seconds=1, nanoseconds=0).to_msg()``, as ``rclpy.duration``.

Not the message: :class:`actions.messages.Duration` (``builtin_interfaces/Duration``, fields
``sec`` and ``nanosec``) is what message fields such as ``time_from_start`` hold, and
:meth:`Duration.to_msg` builds one. The two share a name as they do in ROS 2, so the ROS 2
idiom reads the same with this module's import::

    from actions.duration import Duration        # rclpy: from rclpy.duration import Duration

    point.time_from_start = Duration(seconds=1, nanoseconds=0).to_msg()
"""

from __future__ import annotations

import functools
import math
import numbers
from typing import Any

from actions import messages
from wbc.core.errors import ConfigurationError

_NANOSECONDS_PER_SECOND = 1_000_000_000


def total_nanoseconds(owner: str, seconds: Any, nanoseconds: Any) -> int:
    """``seconds`` [s] + ``nanoseconds`` [ns] as whole nanoseconds, rounded to the nearest.

    rclpy truncates ``seconds * 1e9``; rounding keeps ``seconds=4.35`` at 4.35 s exactly
    rather than one nanosecond short.

    Args:
        owner: The class being built, for the error message (``"Duration"``).
        seconds: A finite real number of seconds.
        nanoseconds: An integer number of nanoseconds.

    Raises:
        ConfigurationError: Either argument has the wrong type or is not finite.
    """
    if not isinstance(seconds, numbers.Real) or isinstance(seconds, bool) or not math.isfinite(
            seconds):
        raise ConfigurationError(
            f"{owner}(seconds=...) must be a finite real number of seconds; received "
            f"{seconds!r} (type {type(seconds).__name__})"
        )
    if not isinstance(nanoseconds, numbers.Integral) or isinstance(nanoseconds, bool):
        raise ConfigurationError(
            f"{owner}(nanoseconds=...) must be an integer number of nanoseconds; received "
            f"{nanoseconds!r} (type {type(nanoseconds).__name__}); put fractions in seconds"
        )
    if isinstance(seconds, numbers.Integral):  # exact for any size
        return int(seconds) * _NANOSECONDS_PER_SECOND + int(nanoseconds)
    return round(float(seconds) * _NANOSECONDS_PER_SECOND) + int(nanoseconds)


@functools.total_ordering
class Duration:
    """A signed span of time in nanoseconds, as ``rclpy.duration.Duration``.

    Args:
        seconds: Seconds [s], any finite real number.
        nanoseconds: Nanoseconds [ns] added to ``seconds``, an integer.

    Raises:
        ConfigurationError: An argument has the wrong type or is not finite.
    """

    __slots__ = ("_nanoseconds",)

    def __init__(self, *, seconds: float = 0, nanoseconds: int = 0) -> None:
        self._nanoseconds = total_nanoseconds("Duration", seconds, nanoseconds)

    @property
    def nanoseconds(self) -> int:
        """The duration in whole nanoseconds [ns]."""
        return self._nanoseconds

    def to_msg(self) -> messages.Duration:
        """The ``builtin_interfaces/Duration`` message (a negative one has a negative ``sec``)."""
        sec, nanosec = divmod(self._nanoseconds, _NANOSECONDS_PER_SECOND)
        return messages.Duration(sec=sec, nanosec=nanosec)

    @classmethod
    def from_msg(cls, msg: messages.Duration) -> Duration:
        """The duration a ``Duration`` message holds.

        Raises:
            ConfigurationError: ``msg`` is not a :class:`actions.messages.Duration`.
        """
        if not isinstance(msg, messages.Duration):
            raise ConfigurationError(
                f"Duration.from_msg needs an actions.messages.Duration; received {msg!r} "
                f"(type {type(msg).__name__})"
            )
        return cls(seconds=msg.sec, nanoseconds=msg.nanosec)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Duration):
            return NotImplemented
        return self._nanoseconds == other._nanoseconds

    def __lt__(self, other: Duration) -> bool:
        if not isinstance(other, Duration):
            return NotImplemented
        return self._nanoseconds < other._nanoseconds

    def __hash__(self) -> int:
        return hash(self._nanoseconds)

    def __add__(self, other: Duration) -> Duration:
        if not isinstance(other, Duration):
            return NotImplemented
        return Duration(nanoseconds=self._nanoseconds + other._nanoseconds)

    def __sub__(self, other: Duration) -> Duration:
        if not isinstance(other, Duration):
            return NotImplemented
        return Duration(nanoseconds=self._nanoseconds - other._nanoseconds)

    def __repr__(self) -> str:
        return f"Duration(nanoseconds={self._nanoseconds})"
