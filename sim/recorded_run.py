"""A recorded run read back: :func:`load_run` reads an ``--mcap`` recording or a ``--log``
``.npz`` into a :class:`RecordedRun` (its states as arrays, its channels, its lines); a
truncated or foreign file raises :class:`RecordingError` with one line naming the problem.
"""

from __future__ import annotations

import json
import math
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from sim.walking_plot import walked
from wbc.core.errors import WbcError
from wbc.model.description import JOINT_NAMES, LEGS

#: The first and last 8 bytes of every MCAP file.
MCAP_MAGIC = b"\x89MCAP0\r\n"
#: The channel a go2-wbc recording keeps its states on.
STATE_TOPIC = "/wbc/state"
#: What a walk's ``--log`` holds for ``/walking`` besides its ``commanded_velocity`` (logs
#: written before these were added replay without ``/walking``, with a note).
WALKING_ARRAYS = ("measured_velocity", "stance")


class RecordingError(WbcError):
    """A file that is not a readable go2-wbc recording (the message names why)."""


@dataclass
class RawMessage:
    """One message of an MCAP recording as stored: its channel and bytes."""

    topic: str
    log_time_ns: int
    data: bytes


@dataclass
class RecordedRun:
    """A run read back.

    ``arrays``: ``t_s`` (n,), ``q`` (n, 19), ``v`` (n, 18) the controller's state, and when
    the run was simulated ``q_true``, ``v_true``, ``foot_target`` and ``foot_position`` (n, 3)
    of ``raised_leg``, ``contact_forces`` (n, 4, 3), ``com_margin_m``, ``tick_us``, ``phase``
    (the shape :func:`sim.run_recorder.write_plot` reads); a walk's ``commanded_velocity``
    (n, 3) (NaN where nothing walked), which makes that the walking plot; a walk's ``--log``
    also ``measured_velocity`` (n, 3) and ``stance`` (n, 4) (:data:`WALKING_ARRAYS`).
    ``notes``: what the file lacks that a replay would show (said, never an error).
    """

    path: Path
    kind: str  # "mcap" or "npz"
    arrays: dict[str, np.ndarray]
    #: topic -> (schema name, message encoding, schema encoding, schema bytes, count).
    channels: dict[str, tuple[str, str, str, bytes, int]] = field(default_factory=dict)
    #: Every message, in log-time order (MCAP recordings only).
    messages: list[RawMessage] = field(default_factory=list)
    metadata: dict[str, str] = field(default_factory=dict)
    attachments: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def simulated(self) -> bool:
        """The recording holds the simulator's truth (a simulated command's)."""
        return "q_true" in self.arrays

    @property
    def duration_s(self) -> float:
        """Robot time [s] from its first state to its last."""
        t = self.arrays["t_s"]
        return float(t[-1] - t[0]) if len(t) else 0.0

    def caption(self) -> str:
        """The plot's second title line from the recording's metadata (empty without it)."""
        m = self.metadata
        if "plant" not in m:
            return ""
        head = f"plant {m['plant']}, control {m.get('control_rate_hz', '?')} Hz"
        if m.get("state") == "truth":
            return f"{head}; state: the simulator's truth (no estimator)"
        return f"{head}; state estimated by {m.get('estimator', '?')}"

    def describe(self) -> str:
        """One line: what the file holds."""
        states = len(self.arrays["t_s"])
        what = (f"{len(self.channels)} channels, {len(self.messages)} messages, "
                if self.kind == "mcap" else "")
        source = "simulated" if self.simulated else "robot (no simulator truth)"
        return (f"{self.path}: {self.kind.upper()}, {what}{states} states over "
                f"{self.duration_s:.3f} s, {source}")


def load_run(path: Path | str) -> RecordedRun:
    """Read ``path`` (``.mcap`` or ``.npz``).

    Raises:
        RecordingError: A missing, truncated or foreign file, or one without states.
    """
    path = Path(path)
    try:
        head = path.open("rb").read(8)
    except OSError as err:
        raise RecordingError(f"{path}: cannot read it ({err.strerror or err})") from err
    if head == MCAP_MAGIC:
        return _load_mcap(path)
    if head.startswith(b"PK"):
        return _load_npz(path)
    raise RecordingError(f"{path}: not an MCAP recording or an .npz log (it starts with "
                         f"{head!r}; an MCAP file starts with {MCAP_MAGIC!r})")


def _load_mcap(path: Path) -> RecordedRun:
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    size = path.stat().st_size
    with path.open("rb") as f:
        f.seek(max(0, size - 8))
        if f.read(8) != MCAP_MAGIC:
            raise RecordingError(f"{path}: truncated MCAP file ({size} bytes, no closing "
                                 "magic: the recording was cut short before its end was "
                                 "written)")
        f.seek(0)
        run = RecordedRun(path, "mcap", {})
        states: list[dict[str, Any]] = []
        try:
            reader = make_reader(f)
            counts: dict[str, int] = {}
            for schema, channel, message in reader.iter_messages(log_time_order=True):
                counts[channel.topic] = counts.get(channel.topic, 0) + 1
                if channel.topic not in run.channels:
                    run.channels[channel.topic] = (
                        schema.name if schema else "", channel.message_encoding,
                        schema.encoding if schema else "", schema.data if schema else b"", 0)
                run.messages.append(RawMessage(channel.topic, message.log_time, message.data))
                if channel.topic == STATE_TOPIC:
                    states.append(json.loads(message.data))
            for topic, count in counts.items():
                run.channels[topic] = (*run.channels[topic][:4], count)
            for record in reader.iter_metadata():
                run.metadata.update(record.metadata)
            run.attachments = [a.name for a in reader.iter_attachments()]
        except (McapError, ValueError, OSError, EOFError) as err:
            raise RecordingError(f"{path}: unreadable MCAP file "
                                 f"({type(err).__name__}: {err})") from err
    if not states:
        raise RecordingError(f"{path}: an MCAP file without go2-wbc's {STATE_TOPIC} channel "
                             f"(channels: {', '.join(run.channels) or 'none'}); record one "
                             "with --mcap")
    run.arrays = _state_arrays(states)
    rate = run.metadata.get("control_rate_hz", "")
    if rate.replace(".", "", 1).isdigit() and float(rate) > 0:
        run.arrays["control_period_s"] = np.array(1.0 / float(rate))
    return run


def _state_arrays(states: list[dict[str, Any]]) -> dict[str, np.ndarray]:
    """The ``/wbc/state`` messages as arrays (JSON nulls as NaN)."""
    def column(name: str) -> np.ndarray:
        return np.array([s.get(name) for s in states], dtype=float)

    arrays = {"t_s": column("t_s"), "q": column("q"), "v": column("v"), "tau": column("tau"),
              "tick_us": column("tick_us"), "phase": np.array([s["phase"] for s in states]),
              "joint_names": np.array(JOINT_NAMES), "legs": np.array(LEGS)}
    if states[0].get("q_true") is not None:
        leg = states[0].get("raised_leg") or "FR"
        k = LEGS.index(leg)
        arrays.update(q_true=column("q_true"), v_true=column("v_true"),
                      foot_target=column("foot_target")[:, k],
                      foot_position=column("foot_position")[:, k],
                      contact_forces=column("force_n"), com_margin_m=column("com_margin_m"),
                      raised_leg=np.array(leg))
    commanded = [s.get("commanded_velocity") for s in states]
    if any(c is not None for c in commanded):  # a walk: the walking plot's command
        arrays["commanded_velocity"] = np.array(
            [[math.nan] * 3 if c is None else c for c in commanded], dtype=float)
    return arrays


def _load_npz(path: Path) -> RecordedRun:
    try:
        with np.load(path) as data:
            arrays = {name: data[name] for name in data.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
        raise RecordingError(f"{path}: unreadable .npz ({type(err).__name__}: "
                             f"{' '.join(str(err).split())}; truncated?)") from err
    missing = [name for name in ("t_s", "q", "v") if name not in arrays]
    if missing:
        raise RecordingError(f"{path}: not a go2-wbc --log file (no {', '.join(missing)} "
                             f"array; it holds {', '.join(sorted(arrays)) or 'nothing'})")
    if arrays["q"].ndim != 2 or arrays["q"].shape[1:] != (19,):
        raise RecordingError(f"{path}: q has shape {arrays['q'].shape}; expected (n, 19)")
    arrays["q"], arrays["v"] = arrays["q"].astype(float), arrays["v"].astype(float)
    run = RecordedRun(path, "npz", arrays)
    lacking = [name for name in WALKING_ARRAYS if name not in arrays]
    if lacking and walked(arrays):
        run.notes.append(f"{path.name} walked but has no {' or '.join(lacking)} array (a --log "
                         "written before they were logged): replayed without /walking; "
                         "--plot draws the walk as before")
    return run
