"""A recorded run played back on the wall clock: :class:`RunReplay` shows its states in the
MuJoCo viewer and/or re-serves its channels live for Foxglove or Lichtblick.

An MCAP recording is re-served as stored (every channel, its bytes untouched); an ``.npz``
log is turned into the same channels as ``--mcap`` writes
(:class:`~actions.robot.run_recording.RunRecording`) at
:data:`~actions.robot.run_recording.DEFAULT_RATE_HZ`, ``/walking`` among them where a walk's
log holds :data:`~sim.recorded_run.WALKING_ARRAYS` (built as a live run builds it:
:func:`sim.recording_hook.walk_sample`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from actions.robot.run_channels import RunChannels
from actions.robot.run_recording import DEFAULT_RATE_HZ, RunRecording, Snapshot, WalkSample
from sim.recorded_run import WALKING_ARRAYS, RecordedRun
from sim.recording_hook import walk_sample
from wbc.core.errors import ConfigurationError
from wbc.model.description import LEGS


class RunReplay:
    """Plays ``run`` back at ``speed`` times the recorded pace.

    Args:
        run: The recording.
        speed: Played seconds per recorded second (> 0).
        clock, sleep: The wall clock [s] and its sleep (injectable for tests).

    Raises:
        ConfigurationError: A speed that is not a finite number > 0.
    """

    def __init__(self, run: RecordedRun, *, speed: float = 1.0,
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep):
        if not (math.isfinite(speed) and speed > 0.0):
            raise ConfigurationError(f"--speed: expected a number > 0, received {speed!r}")
        self.run, self.speed = run, speed
        self._clock, self._sleep = clock, sleep
        #: States shown and messages re-sent so far.
        self.shown = self.sent = 0

    def play(self, *, view: Any = None, port: int | None = None,
             channels: RunChannels | None = None,
             on_serving: Callable[[int], None] | None = None) -> None:
        """Play the run once: each state to ``view`` (a MuJoCo passive viewer handle on
        ``view.sim``'s model, or ``None``), the channels on ``port`` (``None``: not served).

        Args:
            view: ``(handle, simulator)``: the window and the simulator whose data it shows.
            port: Serve the channels on this local port (0: any free one).
            channels: An ``.npz`` log's channels go here instead (an MCAP file's, say),
                closed at the end; not with ``port``.
            on_serving: Told the port once the server runs.

        Raises:
            ConfigurationError: ``channels`` given with ``port``, or for an MCAP recording
                (re-served as stored, by ``port``).
        """
        run = self.run
        relay = recording = None
        if channels is not None:
            if port is not None or run.kind != "npz":
                raise ConfigurationError(
                    f"channels: take an .npz log's snapshots without a port; received "
                    f"{run.kind} with port {port!r}")
            recording = _npz_recording(run, channels)
        elif port is not None:
            if run.kind == "mcap":
                from actions.robot.run_channels import RelayChannels

                relay = RelayChannels({topic: c[:4] for topic, c in run.channels.items()},
                                      port=port)
                served = relay.port
            else:
                recording = _npz_recording(run, RunChannels(
                    port=port, metadata={"replay": str(run.path)}))
                served = recording.channels.port or port
            if on_serving is not None:
                on_serving(served)
        try:
            self._loop(view, relay, recording)
        finally:
            if relay is not None:
                relay.close()
            if recording is not None:
                recording.close()

    def _loop(self, view: Any, relay: Any, recording: RunRecording | None) -> None:
        run, arrays = self.run, self.run.arrays
        t = arrays["t_s"]
        q_shown = arrays["q_true"] if run.simulated else arrays["q"]
        messages, next_message = run.messages, 0
        start_wall, start_t = self._clock(), (float(t[0]) if len(t) else 0.0)
        every = 1  # an .npz's rows are ticks: the recording's decimation of them
        if recording is not None:
            every = recording.decimation
            for note in run.notes:
                recording.line(f"replay: note: {note}", start_t, level="warning")
        for i, t_s in enumerate(t):
            wait = start_wall + (t_s - start_t) / self.speed - self._clock()
            if wait > 0.0:
                self._sleep(wait)
            if relay is not None:  # every stored message up to this state's time
                limit_ns = round(t_s * 1e9)
                while next_message < len(messages) and (
                        messages[next_message].log_time_ns <= limit_ns):
                    m = messages[next_message]
                    relay.log(m.topic, m.data, m.log_time_ns)
                    next_message += 1
                    self.sent += 1
            if recording is not None and i % every == 0:
                recording.capture(_snapshot(arrays, i))
                recording.drain()
                self.sent += 1
            if view is not None:
                handle, sim = view
                if not handle.is_running():
                    view = None
                    continue
                with handle.lock():
                    sim.reset(q_shown[i])
                handle.sync()
            self.shown += 1
        if relay is not None:  # what came after the last state (the result's lines)
            for m in messages[next_message:]:
                relay.log(m.topic, m.data, m.log_time_ns)
                self.sent += 1


def _npz_recording(run: RecordedRun, channels: RunChannels) -> RunRecording:
    t = run.arrays["t_s"]
    period = float(np.median(np.diff(t))) if len(t) > 1 else 1e-3
    return RunRecording(channels, control_period_s=period,
                        rate_hz=min(DEFAULT_RATE_HZ, 1.0 / period))


def _snapshot(arrays: dict[str, np.ndarray], i: int) -> Snapshot:
    """Row ``i`` of a ``--log`` (a simulated command's or ``run --dds``'s) as a snapshot."""
    targets = np.full((len(LEGS), 3), np.nan)
    target = arrays.get("foot_target")
    if target is not None and target.ndim == 3:  # run --dds: every leg's
        targets[:] = target[i]
    elif target is not None:  # a simulated command's: the raised leg's
        targets[LEGS.index(str(arrays.get("raised_leg", "FR")))] = target[i]
    tau = arrays.get("tau", arrays.get("tau_ff"))
    truth = "q_true" in arrays
    # The schedule's stance where logged (a log before it: the feet without a target).
    stance = arrays["stance"][i] if "stance" in arrays else ~np.isfinite(targets[:, 2])
    return Snapshot(
        t_s=float(arrays["t_s"][i]), q=arrays["q"][i].astype(float),
        v=arrays["v"][i].astype(float),
        tau=np.full(12, np.nan) if tau is None else tau[i].astype(float),
        foot_target=targets, stance=tuple(bool(s) for s in stance),
        tick_us=float(arrays["tick_us"][i]) if "tick_us" in arrays else math.nan,
        qp_ok=bool(arrays["qp_ok"][i]) if "qp_ok" in arrays else True, status="",
        phase=str(arrays["phase"][i]) if "phase" in arrays else "",
        q_true=arrays["q_true"][i] if truth else None,
        v_true=arrays["v_true"][i] if truth else None,
        force_n=arrays["contact_forces"][i] if "contact_forces" in arrays else None,
        com_margin_m=float(arrays["com_margin_m"][i]) if "com_margin_m" in arrays
        else math.nan, walk=_walk(arrays, i))


def _walk(arrays: dict[str, np.ndarray], i: int) -> WalkSample | None:
    """Row ``i``'s ``/walking`` sample: ``None`` where nothing walked or the log predates
    :data:`~sim.recorded_run.WALKING_ARRAYS` (its note says so)."""
    commanded = arrays.get("commanded_velocity")
    if (commanded is None or not np.isfinite(commanded[i]).all()
            or any(name not in arrays for name in WALKING_ARRAYS)):
        return None
    truth = "q_true" in arrays
    forces = arrays.get("contact_forces")
    return walk_sample(commanded[i], arrays["measured_velocity"][i], stance=arrays["stance"][i],
                       q_true=arrays["q_true"][i] if truth else None,
                       v_true=arrays["v_true"][i] if truth else None,
                       forces=None if forces is None else forces[i])
