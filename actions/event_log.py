"""The runner's event log: every status change, feedback and refusal, in simulated time."""

from __future__ import annotations

import threading
from collections import deque
from typing import NamedTuple

from wbc.core.errors import ConfigurationError


class Event(NamedTuple):
    """One entry of the event log."""

    now_s: float
    goal_id: str
    event: str
    detail: str


class EventLog:
    """The latest events, appended by the ticking thread and read from any thread.

    Args:
        maxlen: How many events to keep (oldest dropped first); ``None`` keeps all.

    Raises:
        ConfigurationError: ``maxlen`` is neither ``None`` nor an int >= 1.
    """

    def __init__(self, maxlen: int | None) -> None:
        if maxlen is not None and (not isinstance(maxlen, int) or maxlen < 1):
            raise ConfigurationError(
                f"event_log_maxlen must be None or an int >= 1; received {maxlen!r}"
            )
        self._events: deque[Event] = deque(maxlen=maxlen)
        self._lock = threading.Lock()

    def append(self, now_s: float, goal_id: str, event: str, detail: str) -> None:
        """Add one event (thread-safe)."""
        with self._lock:
            self._events.append(Event(now_s, goal_id, event, detail))

    def snapshot(self) -> list[Event]:
        """A copy of the events, oldest first (thread-safe)."""
        with self._lock:
            return list(self._events)
