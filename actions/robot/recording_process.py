"""A wall-clock run's recording built and written in a child process:
:class:`RecordingProcess`, what ``go2-wbc run --dds --mcap/--foxglove`` records through.

The loop's thread only copies its snapshot into one fixed-size frame (:class:`SnapshotFrame`:
a preallocated float buffer and its few names) and writes it, without blocking, into a pipe
whose kernel buffer is the bounded queue (796 snapshots, 16 s at 50 Hz): a full pipe drops
the snapshot, counted. The child process unpacks the frames and
does everything else (the messages, the MCAP chunks' zstd, the file's writes, the WebSocket
server) with its own interpreter, so none of it runs in the loop's thread or holds its GIL.
A writer *thread* was measured first: its Python work (about 0.3 ms a snapshot) delays the
loop's thread whenever it wakes while the writer holds the GIL (a 0.5 ms sleep's p99
overshoot 0.16 to 0.48 ms without a writer, 0.6 to 1.2 ms with one at 50 Hz).
"""

from __future__ import annotations

import contextlib
import fcntl
import math
import multiprocessing
import os
import pickle
import signal
import struct
from collections import deque
from collections.abc import Sequence
from multiprocessing.process import BaseProcess
from pathlib import Path
from typing import Any

import numpy as np

from actions.robot.run_recording import DEFAULT_RATE_HZ, Snapshot, WalkSample
from actions.robot.tick_stats import SERIES
from wbc.core.errors import ConfigurationError
from wbc.model.description import LEGS

#: The pipe's kernel buffer [bytes] asked for (Linux's default ceiling for a user,
#: ``/proc/sys/fs/pipe-max-size``); the default 64 kB is kept where it is refused.
PIPE_BYTES = 1 << 20
#: Longest wait [s] for the child to open its file and server (imports on a loaded machine).
START_TIMEOUT_S = 120.0
#: Longest wait [s] for the child to finish the file after the last frame.
CLOSE_TIMEOUT_S = 120.0
#: Printed lines held in the parent while the pipe is full (beyond, the oldest is dropped).
PENDING_LINES = 10_000
#: The child's niceness added to the loop's (lower CPU priority; 19 is the lowest).
CHILD_NICENESS = 10
#: A printed line's longest text [bytes of UTF-8] (cut beyond), so that its frame stays
#: within PIPE_BUF (4096 bytes): a larger non-blocking write may be cut by the kernel.
LINE_BYTES = 3_500
#: The float fields of a snapshot frame, in order, with their lengths.
_FLOATS = (("t_s", 1), ("q", 19), ("v", 18), ("tau", 12), ("foot_target", 12),
           ("tick_us", 1), ("com_margin_m", 1), ("estimate_contact", 4), ("q_true", 19),
           ("v_true", 18), ("force_n", 12), ("foot_position", 12), ("stages_us", len(SERIES)),
           ("commanded_velocity", 3), ("measured_velocity", 3), ("flags", 1))
_SLICES: dict[str, slice] = {}
_at = 0
for _name, _n in _FLOATS:
    _SLICES[_name] = slice(_at, _at + _n)
    _at += _n
#: The floats of a snapshot frame.
FRAME_FLOATS = _at
_TEXT_BYTES = 128  # status, phase and raised leg, joined by \x1f, UTF-8, zero-padded
_SNAPSHOT, _LINE = b"S", b"L"
_LENGTH = struct.Struct("!i")  # multiprocessing.Connection's frame header
#: A snapshot frame's bytes on the pipe (at most PIPE_BUF, 4096, so a write is all or none).
FRAME_BYTES = _LENGTH.size + 1 + 8 * FRAME_FLOATS + _TEXT_BYTES
# flags: bits 0-3 stance FL..RR, 4 qp_ok, 5 missed, 6 an estimate, 7 the simulator's truth,
# 8 a motion walks
_QP_OK, _MISSED, _ESTIMATE, _TRUTH, _WALKING = 16, 32, 64, 128, 256


class SnapshotFrame:
    """One snapshot's frame: a preallocated float buffer with a view per field that the tick
    writes into (``frame.q[:] = q``), then :meth:`payload` adds the flags and names.

    Views: ``t_s`` (1,) [s], ``q`` (19,), ``v`` (18,), ``tau`` (12,) [N m],
    ``foot_target`` (4, 3) [m], ``tick_us`` (1,), ``com_margin_m`` (1,),
    ``estimate_contact`` (4,), ``q_true`` (19,), ``v_true`` (18,), ``force_n`` (4, 3) [N],
    ``foot_position`` (4, 3) [m], ``stages_us`` (one per :data:`SERIES`; NaN: none),
    ``commanded_velocity`` and ``measured_velocity`` (3,) a walking motion's, heading frame
    [m/s, m/s, rad/s] (read only when :meth:`payload` is told ``walking``).
    """

    def __init__(self) -> None:
        self.floats = np.zeros(FRAME_FLOATS)
        view = {name: self.floats[part] for name, part in _SLICES.items()}
        self.t_s, self.q, self.v, self.tau = view["t_s"], view["q"], view["v"], view["tau"]
        self.foot_target = view["foot_target"].reshape(4, 3)
        self.tick_us, self.com_margin_m = view["tick_us"], view["com_margin_m"]
        self.estimate_contact = view["estimate_contact"]
        self.q_true, self.v_true = view["q_true"], view["v_true"]
        self.force_n = view["force_n"].reshape(4, 3)
        self.foot_position = view["foot_position"].reshape(4, 3)
        self.stages_us, self._flags = view["stages_us"], view["flags"]
        self.commanded_velocity = view["commanded_velocity"]
        self.measured_velocity = view["measured_velocity"]

    def payload(self, *, stance: Sequence[bool], qp_ok: bool, missed: bool, estimate: bool,
                truth: bool, status: str, phase: str, raised_leg: str = "",
                walking: bool = False) -> bytes:
        """The frame's bytes: the floats as written, whether the estimate's, the truth's and
        the walking motion's fields hold anything, and the names."""
        flags = sum(1 << k for k, leg_stance in enumerate(stance) if leg_stance)
        flags |= ((_QP_OK if qp_ok else 0) | (_MISSED if missed else 0)
                  | (_ESTIMATE if estimate else 0) | (_TRUTH if truth else 0)
                  | (_WALKING if walking else 0))
        self._flags[0] = flags
        text = "\x1f".join((status, phase, raised_leg)).encode()[:_TEXT_BYTES]
        return _SNAPSHOT + self.floats.tobytes() + text.ljust(_TEXT_BYTES, b"\0")


def pack_snapshot(s: Snapshot, frame: SnapshotFrame) -> bytes:
    """``s`` as one frame's payload, written through ``frame``."""
    frame.t_s[0] = s.t_s
    frame.q[:] = s.q
    frame.v[:] = s.v
    frame.tau[:] = s.tau
    frame.foot_target[:] = s.foot_target
    frame.tick_us[0] = s.tick_us
    frame.com_margin_m[0] = s.com_margin_m
    estimate = s.estimate_contact is not None
    if s.estimate_contact is not None:
        frame.estimate_contact[:] = s.estimate_contact
    truth = not (s.q_true is None or s.v_true is None or s.force_n is None
                 or s.foot_position is None)
    if truth:
        frame.q_true[:] = s.q_true
        frame.v_true[:] = s.v_true
        frame.force_n[:] = s.force_n
        frame.foot_position[:] = s.foot_position
    frame.stages_us[:] = [s.stages_us.get(name, math.nan) for name in SERIES]
    walk = s.walk
    if walk is not None:
        frame.commanded_velocity[:] = walk.commanded
        frame.measured_velocity[:] = walk.measured
    return frame.payload(stance=s.stance, qp_ok=s.qp_ok, missed=s.missed, estimate=estimate,
                         truth=truth, status=s.status, phase=s.phase,
                         raised_leg=s.raised_leg, walking=walk is not None)


def unpack_snapshot(payload: bytes) -> Snapshot:
    """The :class:`Snapshot` a :func:`pack_snapshot` payload holds."""
    f = np.frombuffer(payload, dtype=float, count=FRAME_FLOATS, offset=1)
    status, phase, leg = payload[1 + 8 * FRAME_FLOATS:].rstrip(b"\0").decode().split("\x1f")
    flags = int(f[_SLICES["flags"]][0])
    truth = bool(flags & _TRUTH)

    def get(name: str, shape: tuple[int, ...] | None = None) -> np.ndarray:
        a = f[_SLICES[name]].copy()
        return a if shape is None else a.reshape(shape)

    stages = {name: round(float(t), 1)
              for name, t in zip(SERIES, f[_SLICES["stages_us"]], strict=True)
              if math.isfinite(t)}
    return Snapshot(
        t_s=float(f[0]), q=get("q"), v=get("v"), tau=get("tau"),
        foot_target=get("foot_target", (4, 3)),
        stance=tuple(bool(flags & (1 << k)) for k in range(4)),
        tick_us=float(f[_SLICES["tick_us"]][0]), qp_ok=bool(flags & _QP_OK), status=status,
        phase=phase, estimate_contact=get("estimate_contact") if flags & _ESTIMATE else None,
        q_true=get("q_true") if truth else None, v_true=get("v_true") if truth else None,
        force_n=get("force_n", (4, 3)) if truth else None,
        foot_position=get("foot_position", (4, 3)) if truth else None,
        com_margin_m=float(f[_SLICES["com_margin_m"]][0]), raised_leg=leg,
        missed=bool(flags & _MISSED), stages_us=stages,
        walk=None if not flags & _WALKING else WalkSample(
            commanded=get("commanded_velocity"), measured=get("measured_velocity"),
            swing_legs=tuple(leg for k, leg in enumerate(LEGS) if not flags & (1 << k))))


class RecordingProcess:
    """The recording of ``go2-wbc run --dds``: snapshots copied into a pipe at the tick, the
    messages built and written by a child process (module doc).

    Args:
        mcap_path: The MCAP file to write (replaced if it exists); ``None``: none.
        port: The local WebSocket port (0: any free one); ``None``: no server.
        metadata: The run's description, as strings.
        control_period_s: The loop's period [s].
        rate_hz: Snapshots a second of robot time (at most the control rate).

    Raises:
        ConfigurationError: A rate outside ``(0, control rate]``, neither a file nor a port,
            the port cannot be served, or the child did not start.
    """

    def __init__(self, *, mcap_path: Path | str | None = None, port: int | None = None,
                 metadata: dict[str, str] | None = None, control_period_s: float,
                 rate_hz: float = DEFAULT_RATE_HZ):
        control_hz = 1.0 / control_period_s
        if not (math.isfinite(rate_hz) and 0.0 < rate_hz <= control_hz + 1e-9):
            raise ConfigurationError(f"recording rate_hz: expected a rate in (0, "
                                     f"{control_hz:g}] [Hz], received {rate_hz!r}")
        if mcap_path is None and port is None:
            raise ConfigurationError("RecordingProcess: expected an mcap_path, a port or "
                                     "both, received neither")
        #: One snapshot every this many ticks, and the rate that makes [Hz].
        self.decimation = max(1, round(control_hz / rate_hz))
        self.rate_hz = control_hz / self.decimation
        #: Snapshots taken, logged by the child (known once closed), and dropped (the pipe
        #: full, or the child's own queue).
        self.taken = self.logged = self.dropped = 0
        self._ticks = 0
        #: The frame the tick writes its snapshot into (:meth:`capture_frame` sends it).
        self.frame = SnapshotFrame()
        self._pending: deque[bytes] = deque()
        self._port: int | None = None
        #: What went wrong in the child, if anything ("": nothing).
        self.error = ""
        context = multiprocessing.get_context("spawn")  # never fork the DDS threads
        reader, self._pipe = context.Pipe(duplex=False)
        self._control, child_control = context.Pipe(duplex=True)
        try:  # a larger kernel buffer: the bounded queue (module doc)
            fcntl.fcntl(self._pipe.fileno(), fcntl.F_SETPIPE_SZ, PIPE_BYTES)
        except (OSError, AttributeError):
            pass
        #: Snapshots the pipe holds before new ones are dropped.
        self.queue_size = fcntl.fcntl(self._pipe.fileno(), fcntl.F_GETPIPE_SZ) // FRAME_BYTES
        options = {"mcap_path": None if mcap_path is None else str(mcap_path), "port": port,
                   "metadata": dict(metadata or {}), "control_period_s": control_period_s,
                   "rate_hz": self.rate_hz}
        process = context.Process(target=_serve, args=(reader, child_control, options),
                                  name="go2-wbc recording", daemon=True)
        self._process: BaseProcess | None = process
        process.start()
        reader.close()
        child_control.close()
        reply = self._reply(START_TIMEOUT_S, "start")
        if reply[0] == "error":
            self._process.join(10.0)
            self._process = None
            raise ConfigurationError(reply[1])
        self._port = reply[1]
        os.set_blocking(self._pipe.fileno(), False)

    @property
    def port(self) -> int | None:
        """The WebSocket server's port (``None``: no server)."""
        return self._port

    def due(self) -> bool:
        """Count a tick; whether this one is to be snapshotted (every ``decimation``-th)."""
        due = self._ticks % self.decimation == 0
        self._ticks += 1
        return due

    def capture(self, snapshot: Snapshot) -> None:
        """Send ``snapshot`` to the child without blocking (dropped, counted, when the pipe
        is full)."""
        self.capture_frame(pack_snapshot(snapshot, self.frame))

    def capture_frame(self, payload: bytes) -> None:
        """Send a snapshot's frame (:meth:`SnapshotFrame.payload`) without blocking
        (dropped, counted, when the pipe is full)."""
        self.taken += 1
        if self._pending and not self._flush():
            self.dropped += 1
            return
        if not self._send(payload):
            self.dropped += 1

    def line(self, text: str, t_s: float, *, level: str = "info", name: str = "go2-wbc"
             ) -> None:
        """A log line at robot time ``t_s`` [s] (its first :data:`LINE_BYTES`); held here
        while the pipe is full."""
        text = text.encode()[:LINE_BYTES].decode(errors="ignore")
        self._pending.append(_LINE + pickle.dumps((text, t_s, level, name[:100])))
        if len(self._pending) > PENDING_LINES:
            self._pending.popleft()
        self._flush()

    def close(self) -> None:
        """Send what is held, let the child finish the file (its summary) and stop the
        server; ``logged`` and ``dropped`` are then final. Never raises: a child that failed
        is said in :attr:`error`."""
        if self._process is None:
            return
        try:
            os.set_blocking(self._pipe.fileno(), True)
            while self._pending and not self.error:
                self._pipe.send_bytes(self._pending.popleft())
            self._pipe.close()  # the child's end of the frames
            reply = self._reply(CLOSE_TIMEOUT_S, "close")
            self.logged, dropped = reply[1], reply[2]
            self.dropped += dropped
        except (OSError, ConfigurationError) as err:  # said in the summary, not raised
            self.error = self.error or str(err)
        finally:
            self._process.join(CLOSE_TIMEOUT_S)
            self._process = None
            self._control.close()

    def _send(self, payload: bytes) -> bool:
        """One frame written whole, or not at all (a full pipe or a child that ended:
        ``False``; the control loop never sees the recording's failure)."""
        if self.error:
            return False
        frame = _LENGTH.pack(len(payload)) + payload
        try:
            written = os.write(self._pipe.fileno(), frame)
        except BlockingIOError:
            return False
        except OSError as err:  # a broken pipe: the child ended
            self.error = f"the writer process ended ({err.strerror}, exit code {self._exitcode()})"
            return False
        if written != len(frame):  # never within PIPE_BUF; the frames after would be garbled
            self.error = f"a frame of {len(frame)} bytes was cut at {written}"
            return False
        return True

    def _flush(self) -> bool:
        """Send the held lines, in order, while the pipe takes them; whether all went."""
        while self._pending:
            if not self._send(self._pending[0]):
                return False
            self._pending.popleft()
        return True

    def _reply(self, timeout_s: float, what: str) -> tuple[Any, ...]:
        """The child's next reply, or a ConfigurationError naming why there is none."""
        if not self._control.poll(timeout_s):
            raise ConfigurationError(f"recording: the writer process did not {what} within "
                                     f"{timeout_s:g} s (exit code {self._exitcode()})")
        try:
            return tuple(self._control.recv())
        except EOFError as err:
            raise ConfigurationError(f"recording: the writer process ended (exit code "
                                     f"{self._exitcode()})") from err

    def _exitcode(self) -> int | None:
        return None if self._process is None else self._process.exitcode


def _serve(frames: Any, control: Any, options: dict[str, Any]) -> None:
    """The child: open the channels, then turn frames into messages until the pipe closes."""
    from actions.robot.run_channels import RunChannels
    from actions.robot.run_recording import RunRecording

    # Ctrl-C (the process group's SIGINT) is the parent's to handle: it brings the robot to
    # rest, then closes the pipe, and the end of the frames finishes the file here.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    # The recording is best effort, the loop is not: on a busy machine the scheduler serves
    # the loop's process first (the pipe holds 16 s of snapshots while this one waits).
    with contextlib.suppress(OSError):
        os.nice(CHILD_NICENESS)
    try:
        channels = RunChannels(mcap_path=options["mcap_path"], port=options["port"],
                               metadata=options["metadata"])
    except ConfigurationError as err:
        control.send(("error", str(err)))
        return
    recording = RunRecording(channels, control_period_s=options["control_period_s"],
                             rate_hz=options["rate_hz"])
    control.send(("ready", channels.port))
    try:
        while True:
            try:
                payload = frames.recv_bytes()
            except EOFError:  # the parent closed its end: the run is over
                break
            if payload[:1] == _SNAPSHOT:
                recording.capture(unpack_snapshot(payload))
                recording.drain()
            else:
                text, t_s, level, name = pickle.loads(payload[1:])
                recording.line(text, t_s, level=level, name=name)
    finally:
        recording.close()
        control.send(("closed", recording.logged, recording.dropped))
