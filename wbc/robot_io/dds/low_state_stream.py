"""A robot's ``rt/lowstate`` stream as it arrives: its kind, new samples told from repeats, its
rate, and a stream that keeps arriving but never changes: :class:`LowStateStream`.

The kind (:class:`~wbc.robot_io.dds.stream_kind.StreamKind`) is decided from the first
:data:`CLASSIFY_STATES` frames of one framing: the framing from their ``head`` and CRC, and
whether the tick counts from whether it changed between them. Until then a frame of another
framing starts the decision again from it (counted in ``kind_switches``); after, it is dropped
with the reason, as is a frame that fits no framing (a wrong ``head``, a wrong CRC).

New or repeat: in a stream whose tick counts, a frame with the tick of the last new sample is a
repeat (and one whose content changed under that tick is counted in ``tick_frozen``); in one
whose tick does not count (Unitree's Python simulator: 0 always), a frame whose sensor
content (IMU, motors, feet, tick) is the same bytes as the last new sample's is a repeat.
Before the decision a frame is new when either its tick or its content changed.

Rate: the arrival times of the first :data:`RATE_SAMPLES` new samples give the period (their
median interval) and the longest gap; :func:`default_stale_after_s` turns them into the
staleness limit (the module doc of that function says why).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.stream_kind import GO2, StreamKind, framing_of

#: Frames of one framing that decide the kind (at 200 Hz: 25 ms).
CLASSIFY_STATES = 5
#: New samples whose arrival times measure the rate at the start (at 200 Hz: 0.25 s).
RATE_SAMPLES = 50
#: The staleness rule (:func:`default_stale_after_s`): periods, factor of the longest gap
#: seen at the start, floor and ceiling [s].
STALE_PERIODS, STALE_GAP_FACTOR, STALE_MIN_S, STALE_MAX_S = 20.0, 2.0, 0.02, 0.25
_TICK_WRAP = 1 << 32
_NO_FEET = bytes(8)  # foot_force: four int16 zeros


def default_stale_after_s(period_s: float, longest_gap_s: float = 0.0) -> float:
    """The staleness limit [s] for a stream with this period and longest gap [s] at the start.

    ``STALE_PERIODS`` periods, or ``STALE_GAP_FACTOR`` times the longest gap seen, whichever
    is longer, within [``STALE_MIN_S``, ``STALE_MAX_S``]: 20 ms at 1 kHz, 40 ms at 500 Hz,
    100 ms at 200 Hz.

    Why: the limit must outlast the gaps a healthy stream has, or it aborts goals for nothing.
    Unitree's Python simulator sends at 200 Hz with gaps of 10 to 50 ms (10 periods) on a
    loaded 2-core machine; 20 periods is twice that. A GO2 sends at 500 Hz: 40 ms, in which a
    falling body drops g t^2 / 2 = 8 mm. Gaps longer than those measured at the start stretch
    the limit to twice the longest; the ceiling keeps a dead robot's last command from acting
    for longer than a quarter of a second; the floor keeps one late state at 1 kHz (a Python
    controller's garbage collection, up to ~20 ms) from tripping it.
    """
    limit = max(STALE_PERIODS * period_s, STALE_GAP_FACTOR * longest_gap_s)
    return float(min(STALE_MAX_S, max(STALE_MIN_S, limit)))


def _content(record: np.ndarray) -> bytes:
    """The bytes that change with each sample: IMU, motors, feet, tick."""
    return (record["imu_state"].tobytes() + record["motor_state"].tobytes()
            + record["foot_force"].tobytes() + record["tick"].tobytes())


@dataclass
class StreamCounters:
    """What the stream brought since the start (all counts)."""

    #: Frames of a known framing (new samples and repeats).
    frames: int = 0
    #: New samples.
    new_samples: int = 0
    #: Frames that repeated the last new sample (its tick, or its bytes).
    repeats: int = 0
    #: Repeats whose content changed under the same tick (a stream that counts ticks).
    tick_frozen: int = 0
    #: Frames dropped: no framing fits, or not the stream's kind.
    dropped: int = 0
    #: Framings that changed before the kind was decided.
    kind_switches: int = 0
    #: Ticks between two new samples never seen (a GO2-framed stream: one tick a state).
    ticks_skipped: int = 0
    #: A new sample whose tick is before the last one's (the robot restarted).
    tick_restarts: int = 0


class LowStateStream:
    """Classifies and filters the ``LowState_`` frames of one robot (see the module doc).

    Args:
        classify_states: Frames of one framing that decide the kind.
    """

    def __init__(self, *, classify_states: int = CLASSIFY_STATES) -> None:
        if isinstance(classify_states, bool) or not isinstance(classify_states, int) or (
                classify_states < 1):
            raise ConfigurationError(f"classify_states: expected a whole number >= 1, received "
                             f"{classify_states!r}")
        self.classify_states = classify_states
        #: The kind, once decided (``None`` before).
        self.kind: StreamKind | None = None
        self.counters = StreamCounters()
        #: Why the last frame was dropped ('' if none was).
        self.last_fault = ""
        #: Whether any new sample had a non-zero ``foot_force`` (Unitree's simulators send 0).
        self.foot_force_seen = False
        self._framing: str | None = None  # before the decision: the framing being counted
        self._window: list[int] = []  # ... and the ticks of its frames
        self._tick: int | None = None  # the last new sample's tick and content
        self._content = b""
        self._new_s = 0.0  # when it came
        self._since_new = [0, 0, 0]  # repeats, of which content changed; dropped
        self._arrivals: list[float] = []

    # -- each frame -------------------------------------------------------------------------

    def accept(self, record: np.ndarray, now_s: float) -> bool:
        """Whether ``record`` (a ``LowState_`` record, arrived at ``now_s`` [s]) is a new
        sample to use; a repeat or a dropped frame is counted (:attr:`last_fault` says why a
        frame was dropped)."""
        framing, fault = framing_of(record)
        kind = self.kind
        if framing is not None and kind is not None and framing != kind.framing:
            fault = (f"LowState_ framing: the stream is {kind.framing} (head {kind.head}), this "
                     f"frame is {framing}: a second publisher, or a stream that changed kind")
            framing = None
        if framing is None:
            self.counters.dropped += 1
            self._since_new[2] += 1
            self.last_fault = fault
            return False
        self.counters.frames += 1
        tick = int(record["tick"])
        content = _content(record)
        if kind is None:
            if framing != self._framing:
                self.counters.kind_switches += self._framing is not None
                self._framing, self._window = framing, []
            new = tick != self._tick or content != self._content
            if new:
                self._window.append(tick)
        elif kind.ticks:
            new = tick != self._tick
            if not new and content != self._content:
                self.counters.tick_frozen += 1
                self._since_new[1] += 1
        else:
            new = content != self._content
        if not new:
            self.counters.repeats += 1
            self._since_new[0] += 1
            return False
        self._new_sample(record, tick, content, now_s, framing)
        if kind is None and len(self._window) >= self.classify_states:
            self.decide()
        return True

    def decide(self) -> StreamKind | None:
        """Decide the kind now from the frames seen (all of them when fewer than
        ``classify_states`` came: one frame's tick counts unless it is 0); ``None`` if no
        frame of any framing came."""
        if self.kind is None and self._framing is not None:
            # One sample cannot show the tick counting: a tick other than 0 is taken to.
            ticks = set(self._window)
            self.kind = StreamKind(self._framing, ticks=len(ticks) > 1 or ticks != {0})
        return self.kind

    def _new_sample(self, record: np.ndarray, tick: int, content: bytes, now_s: float,
                    framing: str) -> None:
        counters = self.counters
        last = self._tick
        if last is not None and framing == GO2 and tick != last:
            step = (tick - last) % _TICK_WRAP
            if step < _TICK_WRAP // 2:
                counters.ticks_skipped += step - 1
            else:
                counters.tick_restarts += 1
        counters.new_samples += 1
        self._tick, self._content, self._new_s = tick, content, now_s
        self._since_new = [0, 0, 0]
        if not self.foot_force_seen and record["foot_force"].tobytes() != _NO_FEET:
            self.foot_force_seen = True
        if len(self._arrivals) < RATE_SAMPLES:
            self._arrivals.append(now_s)

    # -- what it says -----------------------------------------------------------------------

    @property
    def period_s(self) -> float:
        """The median interval [s] between the first new samples (NaN before two)."""
        gaps = np.diff(self._arrivals)
        return float(np.median(gaps)) if gaps.size else float("nan")

    @property
    def longest_gap_s(self) -> float:
        """The longest interval [s] between the first new samples (0 before two)."""
        gaps = np.diff(self._arrivals)
        return float(gaps.max()) if gaps.size else 0.0

    @property
    def rate_samples(self) -> int:
        """How many new samples the rate was measured on."""
        return len(self._arrivals)

    def stale_after_s(self) -> float:
        """The staleness limit [s] for this stream (:func:`default_stale_after_s`); the
        ceiling when the rate is unknown (fewer than two samples)."""
        period = self.period_s
        if not np.isfinite(period):
            return STALE_MAX_S
        return default_stale_after_s(period, self.longest_gap_s)

    @property
    def foot_force_absent(self) -> bool:
        """Every new sample so far had ``foot_force`` 0 (Unitree's simulators send 0)."""
        return self.counters.new_samples > 0 and not self.foot_force_seen

    def stale_reason(self, now_s: float) -> str:
        """What arrived since the last new sample, in words, when frames did: frames that
        keep arriving but never change (named as such), or only dropped frames; '' when
        nothing arrived since (the estimator's "no sensor sample" says it)."""
        age_ms = (now_s - self._new_s) * 1e3
        repeats, changed, dropped = self._since_new
        if repeats:
            if changed:
                why = (f"its tick stays at {self._tick} while its content changes (a stream "
                       f"whose tick counted froze)")
            else:
                why = (f"the same bytes each time (tick {self._tick}): a frozen sensor stream")
            return (f"rt/lowstate keeps arriving ({repeats} state(s) in the last "
                    f"{age_ms:.0f} ms) but never changes: {why}")
        if dropped:
            return (f"{dropped} rt/lowstate frame(s) in the last {age_ms:.0f} ms, all dropped, "
                    f"the last because {self.last_fault}")
        return ""

    def describe(self) -> str:
        """What was recognised, at the start: the kind, its checks, the measured rate, the
        staleness limit it gives, and whether the feet's force is absent."""
        kind = self.kind
        if kind is None:
            return "rt/lowstate: no frame of a known kind yet"
        rate = (f"{1.0 / self.period_s:.0f} Hz measured over {self.rate_samples} states "
                f"(longest gap {self.longest_gap_s * 1e3:.1f} ms)"
                if np.isfinite(self.period_s) else "rate not measured")
        feet = ("; foot_force absent (0 in every state so far): the feet's contact comes from "
                "the schedule" if self.foot_force_absent else "")
        return f"rt/lowstate: {kind.describe()}; {rate}{feet}"

    def report(self) -> dict[str, object]:
        """The kind, the rate and the counters, JSON-ready."""
        kind = self.kind
        return {
            "kind": None if kind is None else kind.framing,
            "tick_counts": None if kind is None else kind.ticks,
            "checks": None if kind is None else kind.checks(),
            "period_s": self.period_s, "longest_gap_s": self.longest_gap_s,
            "rate_samples": self.rate_samples, "foot_force_absent": self.foot_force_absent,
            **asdict(self.counters),
        }
