"""What a bridge run counted and timed: :class:`BridgeStats` (states, commands, latency, pacing).

Definitions (``tick`` is the ``LowState_.tick`` the bridge publishes, +1 a message; a controller
echoes the tick of the state its command answers in ``LowCmd_.reserve``):

- ``states_published``: ``LowState_`` messages written (one ``rt/wbc/sim/truth`` each).
- ``commands_received``: valid DDS samples taken from ``rt/lowcmd`` by the physics steps,
  good or bad; equal to ``applied + rejected + superseded + in_flight``. With the
  controller's ``commands_sent`` (its ``commands_unmatched`` went to no reader): ``sent -
  unmatched = received + after_stop + lost``, where ``lost`` is what the wire really lost
  (or, when ``command_history_full`` is not 0, what a full reader overwrote).
- ``commands_applied``: handed to the motor drivers (after any simulated delay).
- ``commands_rejected``: dropped, by reason: ``head``, ``level_flag``, ``crc`` (what the robot
  checks, :func:`wbc.robot_io.dds.low_cmd_conversion.low_cmd_fault`), ``motor_cmd`` (values a
  driver refuses: a mode other than 0x00/0x01, a negative or non-finite gain or target, a
  stop sentinel under a gain, a feed-forward torque beyond the effort limit) and ``frame``
  (bytes that do not decode as a ``LowCmd_``).
- ``commands_superseded``: valid, but a newer one came in the same physics step (a robot's
  KeepLast 1 reader would have overwritten it): never applied, not lost.
- ``commands_after_stop``: taken when the bridge closed, after its last physics step.
- ``command_history_full``: physics steps that found the reader's whole history pending
  (:data:`sim.command_intake.COMMAND_HISTORY`): older commands may have been overwritten unseen.
- ``replies_lost``: ticks no valid command answered, between two that one did: for
  consecutive valid commands answering ticks ``a`` then ``b > a``, ``b - a - 1``: the states
  no command that arrived answered (every command that arrives is seen, superseded ones
  too). A state the controller skipped (two arrived within one of its ticks) is one; states
  after the last answered one are not counted (they may still be answered).
- ``replies_repeated``: valid commands answering a tick no newer than the previous one's.
- ``replies_unmatched``: valid commands whose ``reserve`` is no tick of the last
  :data:`RING_TICKS` published (a controller that does not echo sends 0): no latency.
- ``received_ms``: state-to-command latency, from writing a state to receiving the command
  that answers it (the bridge waits on its command reader between physics steps and stamps
  each arrival; one that arrives during a step is stamped when the step takes it), on the
  bridge's clock.
- ``latency_ms``: from writing a state to the physics step that applies its reply ("taken":
  the received latency plus the wait for the next 1 ms step).
- ``reply_ms``: from writing a state to the controller writing its reply (the DDS source
  timestamp; both clocks are the host's realtime clock, so it holds for a controller on the
  same host only).
- ``publish_interval_ms``: time between consecutive ``LowState_`` writes (jitter).
- ``overruns``: times the physics fell more than a few steps behind the wall clock and the
  pacing was resynchronised (the steps missed are not made up).
- ``timeouts``: times the command timeout sent the motors to damping.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: How many published ticks the latency ring remembers (16 s at 1 kHz).
RING_TICKS = 1 << 14
_WRAP = 1 << 32


class Samples:
    """A growing series of floats, kept in NumPy chunks (no list of Python floats)."""

    _CHUNK = 1 << 14

    def __init__(self) -> None:
        self._chunks: list[np.ndarray] = []
        self._current = np.empty(self._CHUNK)
        self._count = 0  # in the current chunk

    def add(self, value: float) -> None:
        """Append one value."""
        if self._count == self._CHUNK:
            self._chunks.append(self._current)
            self._current = np.empty(self._CHUNK)
            self._count = 0
        self._current[self._count] = value
        self._count += 1

    def __len__(self) -> int:
        return len(self._chunks) * self._CHUNK + self._count

    def values(self) -> np.ndarray:
        """Every value, in order (a new array)."""
        return np.concatenate([*self._chunks, self._current[:self._count]])

    def summary(self, scale: float = 1.0) -> dict[str, float | int | None]:
        """``count``, ``median``, ``p99``, ``max`` and ``min`` of the values times ``scale``
        (``None`` when there are none)."""
        values = self.values() * scale
        if not len(values):
            return {"count": 0, "median": None, "p99": None, "max": None, "min": None}
        median, p99 = np.percentile(values, [50.0, 99.0])
        return {"count": len(values), "median": float(median), "p99": float(p99),
                "max": float(values.max()), "min": float(values.min())}


class BridgeStats:
    """The counters and timings of one bridge run (see the module docstring)."""

    def __init__(self) -> None:
        self.states_published = 0
        self.commands_received = 0
        self.commands_applied = 0
        self.commands_superseded = 0
        self.commands_in_flight = 0
        self.commands_after_stop = 0
        self.command_history_full = 0
        #: Rejected commands by reason, and the last message of each reason.
        self.commands_rejected: dict[str, int] = {}
        self.last_rejection: dict[str, str] = {}
        self.replies_lost = 0
        self.replies_repeated = 0
        self.replies_unmatched = 0
        self.overruns = 0
        self.timeouts = 0
        #: Latency samples [s]: to the reply's arrival; to the step that takes it; to the
        #: controller's write.
        self.received = Samples()
        self.latency = Samples()
        self.reply = Samples()
        #: Intervals between consecutive state writes [s].
        self.publish_interval = Samples()
        self._ring_tick = np.full(RING_TICKS, -1, dtype=np.int64)
        self._ring_s = np.zeros(RING_TICKS)
        self._ring_ns = np.zeros(RING_TICKS, dtype=np.int64)
        self._last_publish_s: float | None = None
        self._first_publish_s: float | None = None
        self._last_reply: int | None = None

    def published(self, tick: int, now_s: float, wall_ns: int) -> None:
        """A state with ``tick`` was written at ``now_s`` [s] on the bridge's clock and
        ``wall_ns`` [ns] on the realtime clock."""
        self.states_published += 1
        slot = tick % RING_TICKS
        self._ring_tick[slot] = tick
        self._ring_s[slot] = now_s
        self._ring_ns[slot] = wall_ns
        if self._last_publish_s is not None:
            self.publish_interval.add(now_s - self._last_publish_s)
        else:
            self._first_publish_s = now_s
        self._last_publish_s = now_s

    def rejected(self, reason: str, message: str) -> None:
        """A command was dropped for ``reason`` (``message`` says what was wrong)."""
        self.commands_rejected[reason] = self.commands_rejected.get(reason, 0) + 1
        self.last_rejection[reason] = message

    def replied(self, reply_tick: int, now_s: float, source_ns: int | None, *,
                received_s: float | None = None) -> None:
        """A valid command answering ``reply_tick`` arrived at ``received_s`` [s] (``None``:
        ``now_s``) and was taken at ``now_s`` [s]; the controller wrote it at ``source_ns``
        [ns] (realtime clock; ``None``: unknown)."""
        slot = reply_tick % RING_TICKS
        if reply_tick == 0 or self._ring_tick[slot] != reply_tick:
            self.replies_unmatched += 1
            return
        published_s = self._ring_s[slot]
        self.received.add((now_s if received_s is None else received_s) - published_s)
        self.latency.add(now_s - published_s)
        if source_ns:
            self.reply.add((source_ns - int(self._ring_ns[slot])) * 1e-9)
        if self._last_reply is not None:
            step = (reply_tick - self._last_reply) % _WRAP
            if step == 0 or step >= _WRAP // 2:  # the same tick, or an older one
                self.replies_repeated += 1
                return
            self.replies_lost += step - 1
        self._last_reply = reply_tick

    @property
    def publish_rate_hz(self) -> float | None:
        """States per second between the first and the last write (``None`` before two)."""
        if self._first_publish_s is None or self._last_publish_s is None or (
                self.states_published < 2):
            return None
        return (self.states_published - 1) / (self._last_publish_s - self._first_publish_s)

    def as_dict(self) -> dict[str, Any]:
        """Every counter, and the timings' median, p99, max and min in milliseconds."""
        return {
            "states_published": self.states_published,
            "publish_rate_hz": self.publish_rate_hz,
            "publish_interval_ms": self.publish_interval.summary(1e3),
            "commands_received": self.commands_received,
            "commands_applied": self.commands_applied,
            "commands_rejected": dict(self.commands_rejected),
            "last_rejection": dict(self.last_rejection),
            "commands_superseded": self.commands_superseded,
            "commands_in_flight": self.commands_in_flight,
            "commands_after_stop": self.commands_after_stop,
            "command_history_full": self.command_history_full,
            "replies_lost": self.replies_lost,
            "replies_repeated": self.replies_repeated,
            "replies_unmatched": self.replies_unmatched,
            "received_ms": self.received.summary(1e3),
            "latency_ms": self.latency.summary(1e3),
            "reply_ms": self.reply.summary(1e3),
            "overruns": self.overruns,
            "timeouts": self.timeouts,
        }

    def summary_lines(self) -> list[str]:
        """The summary the command line prints at exit."""
        interval = self.publish_interval.summary(1e3)
        rate = self.publish_rate_hz
        lines = [f"states published {self.states_published}"
                 + ("" if rate is None else
                    f" at {rate:.1f} Hz (interval median {interval['median']:.3f} ms, p99 "
                    f"{interval['p99']:.3f} ms, max {interval['max']:.3f} ms)")
                 + f"; physics overruns {self.overruns}"]
        rejected = sum(self.commands_rejected.values())
        reasons = ", ".join(f"{reason} {count}" for reason, count
                            in sorted(self.commands_rejected.items()))
        lines.append(
            f"commands received {self.commands_received}, applied {self.commands_applied}, "
            f"rejected {rejected}" + (f" ({reasons})" if reasons else "")
            + f", superseded {self.commands_superseded}, after the stop "
            f"{self.commands_after_stop}" + (
                f" (reader history full {self.command_history_full} times: some may have "
                "been overwritten unseen)" if self.command_history_full else "")
            + f"; replies lost {self.replies_lost} (states no command answered), "
            f"repeated {self.replies_repeated}, unmatched {self.replies_unmatched}; "
            f"timeouts to damping {self.timeouts}")
        for reason, message in sorted(self.last_rejection.items()):
            lines.append(f"last {reason} rejection: {message}")
        for name, samples in (("state -> command received", self.received),
                              ("state -> command taken", self.latency),
                              ("state -> controller's write", self.reply)):
            s = samples.summary(1e3)
            if s["count"]:
                lines.append(f"latency {name}: median {s['median']:.2f} ms, p99 "
                             f"{s['p99']:.2f} ms, max {s['max']:.2f} ms ({s['count']} commands)")
        return lines
