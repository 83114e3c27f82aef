"""The QoS of unitree_sdk2's channels, in one place for both ends of the GO2's topics:
:func:`sdk_writer_qos` and :func:`sdk_reader_qos`.

unitree_sdk2 (C++ and Python) writes Reliable (blocking at most 100 ms) KeepLast 1 and reads
BestEffort KeepLast 1. A Reliable writer matches a BestEffort reader (the reader asks less), so
the controller's and the robot's ends match each other and Unitree's own peers. Readers that
must count every sample (the simulated robot's command reader, the bring-up listener) keep a
deeper history: still BestEffort, as a robot's reader is.
"""

from __future__ import annotations

from cyclonedds.core import Policy, Qos
from cyclonedds.util import duration

from wbc.core.errors import ConfigurationError

#: Longest a Reliable write blocks on a full history [ms] (unitree_sdk2's).
MAX_BLOCKING_MS = 100


def sdk_writer_qos() -> Qos:
    """unitree_sdk2's writer: Reliable (blocking at most :data:`MAX_BLOCKING_MS`), KeepLast 1."""
    return Qos(Policy.Reliability.Reliable(duration(milliseconds=MAX_BLOCKING_MS)),
               Policy.History.KeepLast(1))


def sdk_reader_qos(depth: int = 1) -> Qos:
    """unitree_sdk2's reader: BestEffort, KeepLast ``depth`` (1: only the newest is held).

    Raises:
        ConfigurationError: ``depth`` is not an int of at least 1.
    """
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise ConfigurationError(
            f"depth: expected a history depth, an int >= 1 [samples], received {depth!r}")
    return Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(depth))
