"""Input checks shared by the library: shapes, finiteness, ranges; each message names the field."""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

import numpy as np

from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError


def is_finite_real(value: Any) -> bool:
    """Whether ``value`` is a finite real number (``bool`` excluded; NumPy scalars included)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def as_vector(name: str, value: Any, size: int, *, finite: bool = True) -> np.ndarray:
    """Return ``value`` as a float64 vector of length ``size``.

    Args:
        name: Field name used in the error message.
        value: Anything NumPy can turn into an array.
        size: Expected length.
        finite: Also reject NaN and infinite entries.

    Raises:
        ConfigurationError: Wrong shape or not numeric.
        NonFiniteError: A NaN or infinite entry when ``finite`` is set.
    """
    if type(value) is np.ndarray and value.dtype == np.float64 and value.shape == (size,):
        array = value.copy()  # the common case, without NumPy's conversion machinery
    else:
        try:
            array = np.array(value, dtype=np.float64)  # a copy: callers keep their own arrays
        except (TypeError, ValueError) as err:
            raise ConfigurationError(
                f"{name}: expected {size} numbers, received {value!r}"
            ) from err
        if array.shape != (size,):
            raise ConfigurationError(
                f"{name}: expected an array of shape ({size},), received shape {array.shape}"
            )
    # A finite dot product means finite entries; only when it is not (a NaN, an infinity,
    # or an overflow of huge finite values) are the entries checked one by one.
    if finite and not math.isfinite(array @ array) and not np.all(np.isfinite(array)):
        bad = np.flatnonzero(~np.isfinite(array)).tolist()
        raise NonFiniteError(f"{name}: non-finite value at index {bad}: {array.tolist()}")
    return array


def as_float(name: str, value: Any, *, low: float | None = None, high: float | None = None,
             low_inclusive: bool = True) -> float:
    """Return ``value`` as a finite float inside ``[low, high]``.

    Raises:
        ConfigurationError: Not a number, or out of range (the message gives the range).
        NonFiniteError: NaN or infinite.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ConfigurationError(f"{name}: expected a number, received {value!r}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond the float range
        raise ConfigurationError(
            f"{name}: expected a number within the float range (about +-1.8e308), received "
            f"an integer of {len(str(abs(int(value))))} digits"
        ) from None
    if not np.isfinite(number):
        raise NonFiniteError(f"{name}: expected a finite number, received {number}")
    too_low = low is not None and (number < low if low_inclusive else number <= low)
    if too_low or (high is not None and number > high):
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        bracket = "[" if low_inclusive else "("
        raise ConfigurationError(
            f"{name}: expected a value in {bracket}{lo}, {hi}], received {number:g}"
        )
    return number


def as_whole_number(name: str, value: Any, meaning: str) -> int:
    """Return ``value`` as an ``int`` if it is a whole number (Python's or NumPy's, not a
    ``bool``).

    Raises:
        ConfigurationError: Anything else; the message says what the number is
            (``meaning``).
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ConfigurationError(
            f"{name}: expected a whole number ({meaning}), received {value!r}")
    return int(value)


def check_name(kind: str, name: str, valid: Iterable[str]) -> str:
    """Return ``name`` if it is one of ``valid``, else raise listing every valid name."""
    valid = list(valid)
    if name not in valid:
        raise UnknownNameError(
            f"unknown {kind} {name!r}; valid {kind}s: {', '.join(valid)}"
        )
    return name


_Class = TypeVar("_Class", bound=type)


def known_fields_only(kind: str) -> Callable[[_Class], _Class]:
    """Class decorator for a dataclass: an unknown keyword raises :class:`UnknownNameError`
    naming it and listing the valid fields (instead of Python's bare ``TypeError``).

    Args:
        kind: What a field is called in the message (``"sensor parameter"``).
    """
    def decorate(cls: _Class) -> _Class:
        init = cls.__init__
        names = tuple(f.name for f in dataclasses.fields(cls))

        @functools.wraps(init)
        def __init__(self: Any, *args: Any, **kwargs: Any) -> None:
            for key in kwargs:
                check_name(kind, key, names)
            init(self, *args, **kwargs)

        cls.__init__ = __init__  # type: ignore[method-assign]
        return cls

    return decorate
