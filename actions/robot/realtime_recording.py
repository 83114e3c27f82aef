"""A wall-clock run (``go2-wbc run --dds``) into a
:class:`~actions.robot.recording_process.RecordingProcess`: :class:`RealtimeRecording`, a
:class:`~actions.robot.realtime_loop.RealtimeLoop` callback.

The tick only copies its snapshot into the recording's pipe, every ``decimation``-th tick;
the messages are built and written in the recording's child process, never in the loop's
thread (a full pipe drops the snapshot, counted).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from actions.robot.recording_process import RecordingProcess
from actions.robot.tick_log import FootTargets
from actions.robot.tick_stats import SERIES
from wbc.model.description import LEGS

if TYPE_CHECKING:
    from actions.robot.realtime_loop import RealtimeLoop
    from actions.robot.robot_loop import RobotLoop
    from actions.robot.run_recording import RecordedWalking

_TICK = SERIES.index("tick")


class RealtimeRecording:
    """Snapshots a wall-clock loop's ticks every ``recording.decimation`` ticks into
    ``recording`` (its child process logs them).

    Args:
        recording: Where the snapshots go.
        walking_of: The walking motion the loop's goal runs now, ``None`` when nothing walks
            (``sim.gait_view.walking_motion``); its commanded and measured velocity go on
            ``/walking`` (about 10 us a snapshot while walking). Default: none recorded.
    """

    def __init__(self, recording: RecordingProcess, *,
                 walking_of: Callable[[RobotLoop], RecordedWalking | None] | None = None):
        self.recording = recording
        self._walking_of = walking_of
        self._targets: FootTargets | None = None
        self._declared = False

    def __call__(self, rt: RealtimeLoop) -> None:
        if self.recording.due():
            self._capture(rt)

    def _capture(self, rt: RealtimeLoop) -> None:
        """The tick's snapshot written into the recording's preallocated frame, then sent."""
        loop = rt.loop
        controller = loop.controller
        if not self._declared:  # once: an isinstance on a protocol costs microseconds
            self._declared = True
            self._targets = controller if isinstance(controller, FootTargets) else None
        frame = self.recording.frame
        context = loop.context
        frame.t_s[0] = context.now_s
        frame.q[:] = context.q
        frame.v[:] = context.v
        out = rt.last_output
        if out is None:
            frame.tau.fill(math.nan)
        else:
            frame.tau[:] = out.tau
        stance = controller.schedule.stance
        frame.foot_target.fill(math.nan)
        if self._targets is not None:
            for k, leg in enumerate(LEGS):
                if not stance[k]:
                    target = self._targets.foot_target(leg)
                    if target is not None:
                        frame.foot_target[k] = target
        times = rt.last_times  # the previous tick's, complete
        frame.tick_us[0] = times[_TICK] * 1e6
        np.multiply(times, 1e6, out=frame.stages_us)
        frame.com_margin_m[0] = math.nan
        estimator = loop.estimator
        if estimator is not None:
            frame.estimate_contact[:] = estimator.estimate.contact
        goals = loop.runner.active_goals()
        walking = None if self._walking_of is None or not goals else self._walking_of(loop)
        if walking is not None:
            frame.commanded_velocity[:] = walking.commanded_velocity
            frame.measured_velocity[:] = walking.measured_velocity
        self.recording.capture_frame(frame.payload(
            stance=stance, qp_ok=out is not None and bool(out.ok), missed=rt.missed,
            estimate=estimator is not None, truth=False,
            status="DAMPING" if out is None else out.status.name,
            phase=(goals[0].server.action_name if goals else rt.rest.phase.name.lower()),
            walking=walking is not None))
