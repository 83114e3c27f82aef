"""Messages: the base class that checks their fields, and ``builtin_interfaces``' Duration and Time.

A message type is a ``@dataclass(slots=True)`` subclass of :class:`Message`, declared from its
``.action`` file (:meth:`actions.action_type.ActionType.from_file` checks the declaration
against the file, or builds the class from it). The ROS 2 analogues are the generated Python
classes of ``builtin_interfaces``, ``std_msgs``, ``trajectory_msgs`` and ``control_msgs``
(e.g. ``FollowJointTrajectory.Goal``). Like those, every message can be built with no
arguments (numbers 0, strings and arrays empty, nested messages built empty) and then filled
field by field, nested messages included::

    goal = FollowJointTrajectoryGoal()
    goal.trajectory.joint_names = ["FR_calf_joint"]
    point = JointTrajectoryPoint()
    point.positions = [-1.9]
    point.time_from_start = Duration(sec=1)
    goal.trajectory.points.append(point)

and, as with ROS 2's ``__slots__``, a misspelt field is an error
(:class:`~actions.errors.UnknownFieldError`), not a new attribute.

Fields are checked when a message is built with keywords and again when it is sent (by
:meth:`Message.validated_copy`, which ``ActionClient.send_goal_async`` calls): a wrong type
raises :class:`~wbc.core.errors.ConfigurationError` naming the field (as a path from the message
built or sent, e.g. ``FollowJointTrajectoryGoal.trajectory.points[0].positions[1]``), the
value received and what is valid. Plain assignments are not checked on the spot, so a
message may pass through invalid states while it is being filled. Numbers are normalised
(``int`` -> ``float`` for float fields, NumPy scalars -> Python ones), array fields accept
any sequence (a tuple, a NumPy array) and are stored as lists, and any field of type
:class:`Duration` or :class:`Time` also accepts a number of seconds or an rclpy-style
:class:`actions.duration.Duration` / :class:`actions.time.Time` (their ``to_msg()``):
``JointTrajectoryPoint(positions=[0.1], time_from_start=3.0)``.

A sent goal is safe from later changes: the server receives a validated deep copy, so a
client that keeps mutating its message afterwards changes nothing on the server.
"""

from __future__ import annotations

import dataclasses
import functools
import numbers
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from actions.errors import UnknownFieldError
from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real

_NANOSECONDS_PER_SECOND = 1_000_000_000


class Message:
    """Base class of every message: checks and normalises the fields, refuses unknown ones.

    Subclasses are ``@dataclass(slots=True)`` classes (or add ``__slots__ = ()``), so that
    setting a field that does not exist raises instead of adding an attribute.
    """

    __slots__ = ()

    def __post_init__(self) -> None:
        self._normalise(type(self).__name__)

    if not typing.TYPE_CHECKING:  # hidden from type checkers: a misspelt field a type error

        def __setattr__(self, name: str, value: Any) -> None:
            try:
                object.__setattr__(self, name, value)
            except AttributeError:
                raise UnknownFieldError(no_such_field(type(self), name)) from None

    def validated_copy(self) -> typing.Self:
        """A deep copy with every field checked and normalised, as at keyword construction.

        This is what a server receives when the message is sent as a goal: nothing the
        sender does to its own message afterwards reaches the copy. The message itself is
        not modified.

        Raises:
            ConfigurationError: A field (at any depth) has the wrong type or value; the
                message names its path from this message, e.g. ``HighFiveGoal.target_height``.
        """
        return self._normalised(type(self).__name__, copy=True)

    def _normalise(self, where: str) -> None:
        """Check and normalise every field in place, nested messages included."""
        for name, hint in field_types(type(self)).items():
            value = getattr(self, name)
            if type(value) is hint and hint in _PLAIN:
                continue  # already normal (most fields of the feedback sent at 50 Hz)
            object.__setattr__(self, name, _coerce(hint, value, f"{where}.{name}", copy=False))
        self._check(where)

    def _normalised(self, where: str, *, copy: bool) -> typing.Self:
        """This message normalised in place (``copy=False``) or a normalised deep copy."""
        if not copy:
            self._normalise(where)
            return self
        cls = type(self)
        duplicate = cls.__new__(cls)
        for name, hint in field_types(cls).items():
            value = _coerce(hint, getattr(self, name), f"{where}.{name}", copy=True)
            object.__setattr__(duplicate, name, value)
        duplicate._check(where)
        return duplicate

    def _check(self, where: str) -> None:
        """Checks beyond each field's type (a Duration's ``nanosec`` range); none by default.

        Args:
            where: How to name this message in an error (its path from the message checked).
        """

    @classmethod
    def coerce(cls, value: Any, where: str) -> typing.Self:
        """``value`` as a message of this type, for a field of this type that is given
        something else than an instance (an instance is normalised instead).

        Nothing is converted by default; :class:`Duration` and :class:`Time` also take a
        number of seconds or an rclpy-style duration or time.

        Raises:
            ConfigurationError: ``value`` is not a ``cls``; the message names the field.
        """
        if isinstance(value, cls):
            return value
        raise ConfigurationError(f"{where} must be a {cls.__name__}; received {_describe(value)}")


def _field_types(cls: type) -> dict[str, Any]:
    """The type of every field of the message class ``cls``, in field order.

    E.g. ``{"target_height": float, "hold_seconds": int}`` for :class:`HighFiveGoal`;
    arrays are ``list[...]``, nested messages their class.
    """
    hints = typing.get_type_hints(cls)
    return {f.name: hints[f.name] for f in dataclasses.fields(cls)}


#: :func:`_field_types`, cached per class. Typed as a plain function: to mypy the cache takes
#: only hashable arguments, and it does not count a class as one when its instances are not.
field_types: Callable[[type], dict[str, Any]] = functools.cache(_field_types)


def no_such_field(cls: type, name: Any, where: str | None = None) -> str:
    """The message for a field ``name`` that ``cls`` does not have, listing the ones it has.

    Args:
        cls: The message class.
        name: The name asked for.
        where: The message's path, when it is nested (``"HighFiveGoal"`` by default).
    """
    fields = ", ".join(field_types(cls))
    at = cls.__name__ if where is None or where == cls.__name__ else f"{where} ({cls.__name__})"
    constant = " (it is a constant)" if isinstance(name, str) and name.isupper() and hasattr(
        cls, name) else ""
    return f"{at} has no field {name!r}{constant}; its fields: {fields}"


def _describe(value: Any) -> str:
    return f"{value!r} (type {type(value).__name__})"


#: Field types whose exact Python instances are already normal (no conversion, no check left).
_PLAIN = frozenset((float, int, bool, str))


def _coerce(hint: Any, value: Any, where: str, *, copy: bool) -> Any:
    """Check ``value`` against the field type ``hint`` and return its normalised form.

    Nested messages are normalised in place, or copied when ``copy`` is true; lists are
    always new lists.
    """
    if type(value) is hint and hint in _PLAIN:
        return value  # what the branches below return for it (feedback at 50 Hz: most fields)
    if typing.get_origin(hint) is list:
        (item_hint,) = typing.get_args(hint)
        if item_hint is float and type(value) is np.ndarray and value.ndim == 1 and (
                value.dtype.kind == "f"):
            return value.tolist()  # what the loop below gives, without a path per element
        if isinstance(value, str | bytes | dict) or not hasattr(value, "__iter__"):
            raise ConfigurationError(
                f"{where} must be a sequence (list, tuple or array); received {_describe(value)}"
            )
        return [
            _coerce(item_hint, item, f"{where}[{i}]", copy=copy) for i, item in enumerate(value)
        ]
    if hint is float:
        if isinstance(value, numbers.Real) and not isinstance(value, bool):
            try:
                return float(value)
            except OverflowError:  # an int beyond the float range
                raise ConfigurationError(
                    f"{where} must be a real number within the float range (about +-1.8e308); "
                    f"received an integer of {len(str(abs(value)))} digits"
                ) from None
        raise ConfigurationError(f"{where} must be a real number; received {_describe(value)}")
    if hint is int:
        if isinstance(value, numbers.Integral) and not isinstance(value, bool):
            return int(value)
        raise ConfigurationError(f"{where} must be an integer; received {_describe(value)}")
    if hint is bool:
        if isinstance(value, bool) or type(value).__name__ == "bool_":  # NumPy's bool
            return bool(value)
        raise ConfigurationError(f"{where} must be True or False; received {_describe(value)}")
    if hint is str:
        if isinstance(value, str):
            return value
        raise ConfigurationError(f"{where} must be a str; received {_describe(value)}")
    if isinstance(hint, type) and issubclass(hint, Message):
        if isinstance(value, hint):
            return value._normalised(where, copy=copy)
        return hint.coerce(value, where)
    if isinstance(hint, type) and isinstance(value, hint):
        return value
    raise ConfigurationError(
        f"{where} must be a {getattr(hint, '__name__', hint)}; received {_describe(value)}"
    )


@dataclass(order=True, slots=True)
class _SecondsNanoseconds(Message):
    """Shared arithmetic of :class:`Duration` and :class:`Time`: whole seconds + nanoseconds.

    ``nanosec`` is always in ``[0, 1e9)``; a negative amount has a negative ``sec``
    (-0.25 s is ``sec=-1, nanosec=750_000_000``), as in ``builtin_interfaces``.
    """

    sec: int = 0
    nanosec: int = 0

    def _check(self, where: str) -> None:
        if not 0 <= self.nanosec < _NANOSECONDS_PER_SECOND:
            raise ConfigurationError(
                f"{where}.nanosec must be in [0, 999999999]; received "
                f"{self.nanosec} (put whole seconds in sec, or use "
                f"{type(self).__name__}.from_seconds)"
            )

    @classmethod
    def from_seconds(cls, seconds: float) -> typing.Self:
        """Build from a number of seconds, rounded to the nearest nanosecond.

        Raises:
            ConfigurationError: ``seconds`` is not a finite real number.
        """
        if not is_finite_real(seconds):
            raise ConfigurationError(
                f"{cls.__name__}.from_seconds needs a finite number of seconds; "
                f"received {_describe(seconds)}"
            )
        sec, nanosec = divmod(
            round(float(seconds) * _NANOSECONDS_PER_SECOND), _NANOSECONDS_PER_SECOND
        )
        return cls(sec=sec, nanosec=nanosec)

    def to_seconds(self) -> float:
        """The amount in seconds, e.g. ``Duration(sec=1, nanosec=500_000_000)`` -> 1.5."""
        return self.sec + self.nanosec / _NANOSECONDS_PER_SECOND

    @classmethod
    def coerce(cls, value: Any, where: str) -> typing.Self:
        """Return ``value`` if it already is a ``cls``, else convert it to one.

        Converted: a finite number of seconds (``cls.from_seconds``), or an object whose
        ``to_msg()`` returns a ``cls`` (the rclpy-style :class:`actions.duration.Duration`
        and :class:`actions.time.Time`).

        Raises:
            ConfigurationError: ``value`` is none of these.
        """
        if isinstance(value, cls):
            return value
        if is_finite_real(value):
            return cls.from_seconds(value)
        to_msg = getattr(value, "to_msg", None)
        if callable(to_msg):
            message = to_msg()
            if isinstance(message, cls):
                return message
        raise ConfigurationError(
            f"{where} must be a {cls.__name__} or a finite number of seconds; "
            f"received {_describe(value)}"
        )


@dataclass(order=True, slots=True)
class Duration(_SecondsNanoseconds):
    """A signed span of time (``builtin_interfaces/Duration``): ``sec`` [s] + ``nanosec`` [ns].

    ``Duration(sec=1)`` is 1.0 s; ``Duration.from_seconds(2.5)`` is ``sec=2, nanosec=5e8``.
    rclpy's ``Duration(seconds=1).to_msg()`` is :class:`actions.duration.Duration`.
    """


@dataclass(order=True, slots=True)
class Time(_SecondsNanoseconds):
    """A point in (simulated) time (``builtin_interfaces/Time``), never negative."""

    def _check(self, where: str) -> None:
        _SecondsNanoseconds._check(self, where)
        if self.sec < 0:
            raise ConfigurationError(
                f"{where} must not be negative; received sec={self.sec}, nanosec={self.nanosec}"
            )


def as_duration(value: Duration | float, name: str = "duration") -> Duration:
    """Accept a :class:`Duration` or a number of seconds where a duration is expected.

    Args:
        value: A ``Duration``, or seconds as an ``int``/``float`` (e.g. ``3.0``).
        name: The argument's name, used in the error message.

    Returns:
        ``value`` itself if it is a ``Duration``, else ``Duration.from_seconds(value)``.

    Raises:
        ConfigurationError: ``value`` is neither a ``Duration`` nor a finite number.
    """
    return Duration.coerce(value, name)
