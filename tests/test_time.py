"""Tests of the rclpy-style Time: construction, the message both ways, arithmetic."""

from __future__ import annotations

import pytest

from actions import messages
from actions.duration import Duration
from actions.time import Time
from wbc.core.errors import ConfigurationError


def test_to_msg_from_msg_and_seconds_nanoseconds() -> None:
    time = Time(seconds=2.5, nanoseconds=1)
    assert time.nanoseconds == 2_500_000_001
    assert time.seconds_nanoseconds() == (2, 500_000_001)
    assert time.to_msg() == messages.Time(sec=2, nanosec=500_000_001)
    assert Time.from_msg(time.to_msg()) == time
    with pytest.raises(ConfigurationError, match="needs an actions.messages.Time"):
        Time.from_msg(messages.Duration())  # type: ignore[arg-type]


def test_arithmetic_with_durations() -> None:
    start, end = Time(seconds=1), Time(seconds=3.5)
    assert end - start == Duration(seconds=2.5)
    assert start + Duration(seconds=0.5) == Time(seconds=1.5) == Duration(seconds=0.5) + start
    assert end - Duration(seconds=3) == Time(seconds=0.5)
    assert start < end and len({start, Time(nanoseconds=1_000_000_000)}) == 1
    assert repr(start) == "Time(nanoseconds=1000000000)"


def test_a_negative_time_is_refused() -> None:
    with pytest.raises(ConfigurationError) as info:
        Time(seconds=1) - Duration(seconds=2)
    assert str(info.value) == (
        "Time must not be negative; received seconds=0, nanoseconds=-1000000000 "
        "(-1000000000 ns in all)"
    )
    with pytest.raises(ConfigurationError, match="must be a finite real number of seconds"):
        Time(seconds=float("inf"))
