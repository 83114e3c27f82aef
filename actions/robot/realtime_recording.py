"""A wall-clock run (``go2-wbc run --dds``) into a
:class:`~actions.robot.recording_process.RecordingProcess`: :class:`RealtimeRecording`, a
:class:`~actions.robot.realtime_loop.RealtimeLoop` callback.

The tick only copies its snapshot into the recording's pipe, every ``decimation``-th tick;
the messages are built and written in the recording's child process, never in the loop's
thread (a full pipe drops the snapshot, counted).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from actions.robot.recording_process import RecordingProcess
from actions.robot.run_recording import Snapshot
from actions.robot.tick_log import FootTargets
from actions.robot.tick_stats import SERIES
from wbc.model.description import LEGS

if TYPE_CHECKING:
    from actions.robot.realtime_loop import RealtimeLoop

_TICK = SERIES.index("tick")


class RealtimeRecording:
    """Snapshots a wall-clock loop's ticks every ``recording.decimation`` ticks into
    ``recording`` (its child process logs them).

    Args:
        recording: Where the snapshots go.
    """

    def __init__(self, recording: RecordingProcess):
        self.recording = recording
        self._targets: FootTargets | None = None
        self._declared = False

    def __call__(self, rt: RealtimeLoop) -> None:
        if self.recording.due():
            self._capture(rt)

    def _capture(self, rt: RealtimeLoop) -> None:
        loop = rt.loop
        controller = loop.controller
        if not self._declared:  # once: an isinstance on a protocol costs microseconds
            self._declared = True
            self._targets = controller if isinstance(controller, FootTargets) else None
        stance = tuple(bool(s) for s in controller.schedule.stance)
        targets = np.full((len(LEGS), 3), np.nan)
        if self._targets is not None:
            for k, leg in enumerate(LEGS):
                if not stance[k]:
                    target = self._targets.foot_target(leg)
                    if target is not None:
                        targets[k] = target
        out = rt.last_output
        times = rt.last_times  # the previous tick's, complete
        estimator = loop.estimator
        goals = loop.runner.active_goals()
        self.recording.capture(Snapshot(
            t_s=loop.context.now_s, q=np.array(loop.context.q), v=np.array(loop.context.v),
            tau=np.full(12, np.nan) if out is None else np.array(out.tau),
            foot_target=targets, stance=stance,
            tick_us=float(times[_TICK]) * 1e6, qp_ok=out is not None and bool(out.ok),
            status="DAMPING" if out is None else out.status.name,
            phase=(goals[0].server.action_name if goals else rt.rest.phase.name.lower()),
            estimate_contact=None if estimator is None
            else np.array(estimator.estimate.contact),
            missed=rt.missed,
            stages_us={name: round(float(t) * 1e6, 1) for name, t in zip(SERIES, times,
                                                                          strict=True)
                       if math.isfinite(t)}))
