"""Tests of the rclpy-style Duration: construction, nanoseconds, the message both ways."""

from __future__ import annotations

import numpy as np
import pytest

from actions import messages
from actions.duration import Duration
from wbc.core.errors import ConfigurationError


def test_seconds_and_nanoseconds_add_up_and_round_to_the_nearest_nanosecond() -> None:
    assert Duration(seconds=1, nanoseconds=0).nanoseconds == 1_000_000_000
    assert Duration(seconds=1.5, nanoseconds=3).nanoseconds == 1_500_000_003
    assert Duration(nanoseconds=7).nanoseconds == 7
    assert Duration().nanoseconds == 0
    assert Duration(seconds=4.35).nanoseconds == 4_350_000_000  # truncation would give ...999
    assert Duration(seconds=np.float64(0.25)).nanoseconds == 250_000_000
    assert Duration(seconds=10**12).nanoseconds == 10**21  # integers stay exact


def test_to_msg_and_from_msg() -> None:
    assert Duration(seconds=1, nanoseconds=0).to_msg() == messages.Duration(sec=1, nanosec=0)
    assert Duration(seconds=2.5).to_msg() == messages.Duration(sec=2, nanosec=500_000_000)
    assert Duration(seconds=-0.25).to_msg() == messages.Duration(sec=-1, nanosec=750_000_000)
    assert Duration(seconds=-0.25).to_msg() == messages.Duration.from_seconds(-0.25)
    message = messages.Duration(sec=3, nanosec=5)
    assert Duration.from_msg(message).to_msg() == message
    with pytest.raises(ConfigurationError, match="needs an actions.messages.Duration"):
        Duration.from_msg(1.0)  # type: ignore[arg-type]


def test_comparisons_arithmetic_and_repr() -> None:
    assert Duration(seconds=1) == Duration(nanoseconds=1_000_000_000)
    assert Duration(seconds=1) < Duration(seconds=1, nanoseconds=1)
    assert Duration(seconds=1) + Duration(seconds=0.5) == Duration(seconds=1.5)
    assert Duration(seconds=1) - Duration(seconds=1.5) == Duration(seconds=-0.5)
    assert len({Duration(seconds=1), Duration(nanoseconds=1_000_000_000)}) == 1
    assert repr(Duration(seconds=1.5)) == "Duration(nanoseconds=1500000000)"
    assert Duration(seconds=1) != messages.Duration(sec=1)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"seconds": "1"},
     "Duration(seconds=...) must be a finite real number of seconds; received '1' (type str)"),
    ({"seconds": float("nan")},
     "Duration(seconds=...) must be a finite real number of seconds; received nan (type float)"),
    ({"nanoseconds": 0.5},
     ("Duration(nanoseconds=...) must be an integer number of nanoseconds; received 0.5 "
      "(type float); put fractions in seconds")),
    ({"seconds": True},
     "Duration(seconds=...) must be a finite real number of seconds; received True (type bool)"),
])
def test_bad_arguments_name_the_argument(kwargs: dict, message: str) -> None:
    with pytest.raises(ConfigurationError) as info:
        Duration(**kwargs)
    assert str(info.value) == message
    with pytest.raises(TypeError):
        Duration(1)  # type: ignore[misc]  # keyword-only, as in rclpy
