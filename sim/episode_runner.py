"""Runs an :class:`sim.episode.Episode`: builds its loop, settles, sends the goal, spins to the end.

The command line, the benchmarks and the sweeps run their episodes here::

    result = EpisodeRunner(Episode(), metrics=True).run()
    print(result.status, result.message, result.metrics.raised_foot_rms_mm)

The runner attaches, at the goal's sending, the hooks the episode and its caller ask for:
the cancel and the pushes (the episode's), the caller's own, then the measuring ones
(metrics on the simulator's truth, per-tick records, video, viewer, pacing), whose wall time
is left out of the metrics' real-time factor. An :class:`EpisodeListener` hears what happens
as it happens (the command line prints from one).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from sim.disturbances import PushSchedule
from sim.episode import GOAL_SLACK_S, Episode
from sim.episode_loop import build_loop
from sim.episode_result import (
    INTERRUPTED,
    NO_GOAL,
    NO_RESULT,
    REJECTED,
    UNAVAILABLE,
    EpisodeEvent,
    EpisodeListener,
    EpisodeResult,
    FeedbackSample,
    feedback_view,
)
from sim.run_recorder import MetricsHook, TickRecorder
from sim.scene_overlay import DEFAULT_OVERLAYS, SceneOverlay
from sim.video_recorder import VideoRecorder
from sim.viewer import Pacer, ViewerHook, window_problem
from wbc.core.errors import WbcError

if TYPE_CHECKING:
    from concurrent.futures import Future

    from actions.client_goal_handle import ClientGoalHandle
    from actions.robot.control_loop import TickHook
    from sim.control_loop import ControlLoop
    from wbc.controller.balance_controller import BalanceController
    from wbc.controller.control_output import ControlOutput


#: A video's frame rate [1/s of sim time] and size [px] unless given.
VIDEO_FPS, VIDEO_SIZE = 30, (640, 480)
#: Statuses after which the loop runs on for the episode's ``after_s``.
_ENDED = ("SUCCEEDED", "CANCELED", "ABORTED")


class RenderingUnavailableError(WbcError):
    """A video was asked for where offscreen rendering cannot start (the GL backend's error)."""


class EpisodeRunner:
    """Runs one :class:`Episode` on a loop built for it here (:attr:`loop`).

    Args:
        episode: The episode.
        controller: The controller (default: :func:`build_loop`'s).
        listener: Hears what happens (nothing by default).
        hooks: More loop hooks, called every tick from the goal's sending on.
        metrics: Measure the episode on the simulator's truth
            (:class:`sim.run_recorder.MetricsHook`).
        record: Record per-tick arrays (:class:`sim.run_recorder.TickRecorder`).
        video: Record an MP4 offscreen to this path (:class:`sim.video_recorder.VideoRecorder`),
            ``video_fps`` frames per second of sim time [1/s], ``video_size`` pixels.
        viewer: Open the MuJoCo viewer (it paces the run to the wall clock); with no window
            possible, the listener is told and the run is headless.
        overlays: What the viewer and the video draw (:mod:`sim.scene_overlay`).
        cancel_reason: The reason the episode's ``cancel_at_s`` cancel gives.
        loop: A loop that has run already, built for this episode's plant and sensors (one
            episode's goal then follows another's); by default a fresh one.
    """

    def __init__(self, episode: Episode, *, controller: BalanceController | None = None,
                 listener: EpisodeListener | None = None, hooks: Sequence[TickHook] = (),
                 metrics: bool = False, record: bool = False, video: Path | None = None,
                 video_fps: int = VIDEO_FPS, video_size: tuple[int, int] = VIDEO_SIZE,
                 viewer: bool = False, overlays: Sequence[str] = DEFAULT_OVERLAYS,
                 cancel_reason: str | None = None, loop: ControlLoop | None = None):
        self.episode = episode
        self.listener = listener or EpisodeListener()
        self.extra_hooks = list(hooks)
        self.want_metrics, self.want_record = metrics, record
        self.video_path, self.video_fps, self.video_size = video, video_fps, video_size
        self.overlays = tuple(overlays)
        if cancel_reason is None and episode.cancel_at_s is not None:
            cancel_reason = f"cancel_at_s {episode.cancel_at_s:g}"
        self.cancel_reason = cancel_reason or ""
        problem = window_problem() if viewer else ""
        if problem:
            self.listener.viewer_unavailable(problem)
        #: A window may open: the run is paced to the wall clock even if opening it fails.
        self.viewer = viewer and not problem
        self.loop = build_loop(episode, controller) if loop is None else loop
        #: The goal's phase and progress, from its last feedback.
        self.phase, self.progress = "", 0.0
        self._trajectory_end_s = episode.trajectory_end_s
        self.handle: ClientGoalHandle | None = None
        self.metrics: MetricsHook | None = None
        self.recorder: TickRecorder | None = None
        self.video: VideoRecorder | None = None
        self.view: ViewerHook | None = None
        self.pacer: Pacer | None = None
        self.pushes: PushSchedule | None = None
        self._overhead = [0.0]
        self._result_future: Future[Any] | None = None
        self._cancel_sent = False
        self._clocks = (0.0, 0.0)
        self._result = EpisodeResult(NO_GOAL, self.loop)

    # ------------------------------------------------------------------ the run

    def run(self, *, tick: Callable[[], object] | None = None) -> EpisodeResult:
        """Settle, attach the hooks, send the goal, spin until its result, run ``after_s``.

        Args:
            tick: What runs one control period from the goal's sending to its result, or
                without a goal for ``after_s`` (default ``loop.spin_once``; a benchmark's
                timed pieces of it).

        Raises:
            RenderingUnavailableError: A video was asked for and cannot be rendered here.
        """
        loop, episode, result = self.loop, self.episode, self._result
        self._wait_until_ready()
        loop.spin_for(episode.settle_s)
        if episode.calibrate_s:
            from actions.robot.foot_calibration import calibrate_standing

            result.calibration = calibrate_standing(loop, duration_s=episode.calibrate_s)
            self.listener.calibrated(result.calibration)
        result.sent_s = loop.robot.time_s
        if episode.action is not None and episode.action not in loop.runner.server_names:
            result.status = UNAVAILABLE
            return result
        closers: list[Callable[[], None]] = []
        try:
            self._attach_hooks(closers)
            self._clocks = (time.perf_counter(), time.process_time())
            if episode.action is None:
                self._stand(tick or loop.spin_once)
            else:
                self._send_and_spin(tick or loop.spin_once)
                if result.status in _ENDED and not result.interrupted:
                    loop.spin_for(episode.after_s)
            wall, cpu = self._clocks
            result.wall_s = time.perf_counter() - wall
            result.cpu_s = time.process_time() - cpu
        finally:
            for close in closers:
                close()
        result.overhead_s = self._overhead[0]
        if self.metrics is not None and result.status not in (REJECTED, INTERRUPTED):
            result.metrics = self.metrics.metrics.summary(
                max(result.wall_s - result.overhead_s, 1e-9))
        return result

    def close(self) -> None:
        """Close the viewer's window, if one is open (it outlives :meth:`run`)."""
        if self.view is not None:
            self.view.close()

    def _send_and_spin(self, tick: Callable[[], object]) -> None:
        loop, episode, result = self.loop, self.episode, self._result
        robot = loop.robot
        self.listener.goal_sending(self, robot.time_s)
        sent = robot.time_s
        self._clocks = (time.perf_counter(), time.process_time())  # what the listener took aside
        handle_future = loop.client(episode.action).send_goal_async(
            episode.goal, feedback_callback=self._on_feedback)
        # Called in the tick that decides, before that tick's feedback.
        handle_future.add_done_callback(self._on_goal_response)
        ticks = 0
        try:
            while not handle_future.done():
                tick()
                ticks += 1
            result_future = self._result_future
            if result_future is None:
                result.status, result.rejection = REJECTED, handle_future.result().rejection
                return
            timeout_s = episode.goal_timeout_s
            deadline, timed_out = sent + timeout_s - 1e-9, False
            while not result_future.done():
                if robot.time_s >= deadline:
                    if timed_out:  # canceled, and no result within the slack: give up
                        break
                    self._cancel("timeout", f"no result after {timeout_s:g} s of sim time")
                    deadline, timed_out = robot.time_s + GOAL_SLACK_S, True
                tick()
                ticks += 1
        except KeyboardInterrupt:
            self._interrupted()
        finally:
            result.ticks, result.sim_s = ticks, robot.time_s - sent
        if self._result_future is not None and self._result_future.done():
            wrapped = self._result_future.result()
            result.status, result.wrapped = wrapped.status.name, wrapped
            self._events.append(EpisodeEvent(loop.context.now_s, "result",
                                             {"status": wrapped.status.name}))
        elif not result.interrupted:
            result.status = NO_RESULT

    def _wait_until_ready(self) -> None:
        """A loop that is not controlling yet (no trustworthy sample at start, or standing up
        after one): the listener is told why, and the goal waits for it, up to the goal's
        timeout (then it is sent anyway and refused with the reason)."""
        loop = self.loop
        estimator = loop.estimator
        if estimator is not None and estimator.start_note:
            self.listener.loop_state(f"state estimator: {estimator.start_note}",
                                     loop.robot.time_s)
        if loop.ready:
            return
        self.listener.loop_state(f"not controlling: {loop.fallback.log.reason}; the motors "
                                 "damp until it can", loop.robot.time_s)
        end = loop.robot.time_s + self.episode.goal_timeout_s - 1e-9
        while not loop.ready and loop.robot.time_s < end:
            loop.spin_once()
        if loop.ready:
            self.listener.loop_state(f"controlling ({loop.fallback.log.summary()})",
                                     loop.robot.time_s)

    def _stand(self, tick: Callable[[], object]) -> None:
        """No goal: ``after_s`` of standing, a ``tick`` a control period."""
        robot, result = self.loop.robot, self._result
        start, ticks = robot.time_s, 0
        end = start + self.episode.after_s - 1e-9
        while robot.time_s < end:
            tick()
            ticks += 1
        result.ticks, result.sim_s = ticks, robot.time_s - start

    def _interrupted(self) -> None:
        """Ctrl-C: cancel the goal and let the robot unwind (a second Ctrl-C stops at once)."""
        loop, result = self.loop, self._result
        result.interrupted, result.status = True, INTERRUPTED
        if self._result_future is None:
            return
        self._cancel("interrupted", "Ctrl-C")
        end = loop.robot.time_s + GOAL_SLACK_S
        while not self._result_future.done() and loop.robot.time_s < end:
            loop.spin_once()

    # ------------------------------------------------------------------ hooks

    def _attach_hooks(self, closers: list[Callable[[], None]]) -> None:
        """The episode's cancel and pushes, the caller's hooks, then the measuring ones."""
        loop, episode = self.loop, self.episode
        hooks: list[TickHook] = []
        if episode.cancel_at_s is not None:
            hooks.append(self._cancel_when_due)
        if episode.pushes:
            self.pushes = PushSchedule(loop.sim, list(episode.pushes))
            hooks.append(self._push_when_due)
        hooks += self.extra_hooks
        timed: list[TickHook] = []
        leg = episode.moving_leg
        if self.want_metrics:
            self.metrics = MetricsHook(loop, lambda: self.phase, leg)
            timed.append(self.metrics)
        if self.want_record:
            self.recorder = TickRecorder(lambda: self.phase, leg, loop)
            timed.append(self.recorder)
        overlay = (SceneOverlay(self.overlays, status_of=lambda: (self.phase, self.progress))
                   if self.overlays else None)
        if self.video_path is not None:
            try:
                self.video = VideoRecorder(loop.sim, self.video_path, fps=self.video_fps,
                                           size=self.video_size, overlay=overlay)
            except Exception as err:  # GL backends fail in assorted types; re-raised as ours
                raise RenderingUnavailableError(" ".join(str(err).split())) from err
            closers.append(self.video.close)
            timed.append(self.video)
        if self.viewer:
            try:
                self.view = ViewerHook(loop.sim, overlay=overlay, on_closed=self._viewer_closed)
            except Exception as err:  # noqa: BLE001 - GLFW and X fail in assorted types
                self.listener.viewer_unavailable(
                    f"cannot open a window ({' '.join(str(err).split())})")
            else:
                timed.append(self.view)
        if episode.realtime or self.viewer:
            self.pacer = Pacer(loop.sim)
            timed.append(self.pacer)
        loop.hooks += hooks + [_Timed(hook, self._overhead) for hook in timed]

    def _cancel_when_due(self, loop: ControlLoop, out: ControlOutput) -> None:
        """The episode's cancel, once at its sim time, while the goal runs."""
        future = self._result_future
        if (self._cancel_sent or future is None or future.done()
                or loop.robot.time_s < self.episode.cancel_at_s - 1e-9):
            return
        self._cancel_sent = True
        self._cancel("cancel_requested", self.cancel_reason)

    def _push_when_due(self, loop: ControlLoop, out: ControlOutput) -> None:
        """The episode's pushes, each once it is due; an event for each applied."""
        pushes = self.pushes
        applied = len(pushes.applied)
        pushes(loop, out)
        for t_s, push, force in pushes.applied[applied:]:
            self._tell(EpisodeEvent(t_s, "push", {
                "force_n": [round(float(f), 3) for f in force],
                "duration_s": push.duration_s, "direction_deg": push.direction_deg}, push))

    def _viewer_closed(self) -> None:
        """The viewer's window went mid-run: the run goes on, unpaced unless the episode
        asked for the wall clock's pace."""
        if self.view is None:
            return
        unpaced = False
        if self.pacer is not None and not self.episode.realtime:
            self.pacer.active, unpaced = False, True
        self.listener.viewer_closed(self.view, unpaced=unpaced)

    # ------------------------------------------------------------------ the action client

    @property
    def _events(self) -> list[EpisodeEvent]:
        return self._result.events

    def _tell(self, event: EpisodeEvent) -> None:
        self._events.append(event)
        self.listener.event(event)

    def _on_goal_response(self, future: Future[ClientGoalHandle]) -> None:
        handle, now = future.result(), self.loop.context.now_s
        self.handle = handle
        if handle.accepted:
            self._result.goal_id = handle.goal_id
            self._result_future = handle.get_result_async()
            self._events.append(EpisodeEvent(now, "accepted"))
        self.listener.goal_response(handle, now)

    def _on_feedback(self, message: Any) -> None:
        phase, progress, error = feedback_view(message.feedback, self._trajectory_end_s)
        self.phase, self.progress = phase, progress
        sample = FeedbackSample(self.loop.context.now_s, phase, progress, error)
        self._result.feedback.append(sample)
        self.listener.feedback(sample, message)

    def _cancel(self, event: str, reason: str) -> None:
        """Ask to cancel the goal; the request is handled on the next tick, at this time."""
        self._tell(EpisodeEvent(self.loop.robot.time_s, event, {"reason": reason}))

        def replied(future: Future[Any]) -> None:
            self.listener.cancel_reply(future.result(), self.loop.context.now_s)

        self.handle.cancel_goal_async().add_done_callback(replied)


class _Timed:
    """Wraps a hook and adds the wall time it takes to ``totals[0]``."""

    def __init__(self, hook: TickHook, totals: list[float]):
        self.hook, self.totals = hook, totals

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        start = time.perf_counter()
        self.hook(loop, out)
        self.totals[0] += time.perf_counter() - start
