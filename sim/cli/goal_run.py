"""One goal of ``go2-wbc high-five``, ``stand``, ``sit`` or ``trajectory``: run, print, write."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from actions.go2.go2_actions import HIGH_FIVE_ACTION
from sim.cli.episode_options import goal_episode
from sim.cli.exit_codes import EXIT_INTERRUPTED, EXIT_UNAVAILABLE, exit_code
from sim.cli.output import FeedbackPrinter, metrics_text, plant_line, run_caption, state_line
from sim.cli.recording_options import open_recording, recording_summary
from sim.episode_loop import startup_objects_frozen
from sim.episode_result import REJECTED, UNAVAILABLE, EpisodeListener, EpisodeResult
from sim.episode_runner import EpisodeRunner, RenderingUnavailableError
from sim.run_plot import write_plot
from wbc.core.errors import ConfigurationError

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from actions.robot.run_recording import RunRecording
    from sim.episode import Episode
    from sim.episode_result import EpisodeEvent, FeedbackSample
    from sim.viewer import ViewerHook


class GoalRun(EpisodeListener):
    """Sends one goal to a fresh simulated GO2, prints what happens, writes the outputs.

    Args:
        args: The parsed options (the episode, outputs, pushes, cancel time, pacing).
        action_name: The action server to send the goal to.
        goal: The goal message.
        goal_text: How to print the goal.
        stream: Where to print (standard output by default).
    """

    def __init__(self, args: argparse.Namespace, action_name: str, goal: Any, goal_text: str,
                 *, stream: IO[str] | None = None):
        self.args = args
        self.action_name = action_name
        self.goal = goal
        self.goal_text = goal_text
        self.stream = stream or sys.stdout
        self.printer = FeedbackPrinter(self.stream, tty=self.stream.isatty())
        self.max_error = 0.0
        #: What the report says of the result (``None`` until the goal was answered).
        self.result: dict[str, Any] | None = None
        #: ``--mcap``/``--foxglove``: the run's channels (every printed line among them).
        self.recording: RunRecording | None = None
        self.runner: EpisodeRunner | None = None

    def say(self, text: str) -> None:
        """One line of output (replacing the progress line)."""
        self.printer.line(text)
        if self.recording is not None:
            now_s = 0.0 if self.runner is None else self.runner.loop.robot.time_s
            self.recording.line(text, now_s)

    def run(self) -> int:
        """Run the goal; return the exit code."""
        args = self.args
        if getattr(args, "foxglove", None) is not None:
            args.realtime = True  # a live view at the robot's pace
        episode = goal_episode(args, self.action_name, self.goal)
        try:
            self.recording = open_recording(args, control_period_s=episode.control_period_s,
                                            metadata=self._metadata(episode))
        except ConfigurationError as err:
            print(f"go2-wbc: {err}", file=sys.stderr)
            return EXIT_UNAVAILABLE
        if self.recording is not None and self.recording.channels.port is not None:
            self.say(f"foxglove: serving ws://127.0.0.1:{self.recording.channels.port}")
        self.say(state_line(episode))
        self.say(plant_line(episode))
        if episode.state == "estimate":
            self.say("feet: " + episode.make_estimator().foot_calibration.describe())
        runner = self.runner = EpisodeRunner(
            episode, listener=self, metrics=args.metrics or args.report is not None,
            record=bool(args.log or args.plot), video=args.video, video_fps=args.fps,
            video_size=args.video_size, viewer=args.viewer, overlays=args.overlay,
            cancel_reason=None if args.cancel_at is None else f"--cancel-at {args.cancel_at:g}")
        with startup_objects_frozen():
            try:
                return self._run(runner, episode)
            finally:
                if self.recording is not None:
                    self.recording.close()
                    self.printer.line(recording_summary(args, self.recording))
                runner.close()  # after the outputs: the window outlives the run

    def _metadata(self, episode: Episode) -> dict[str, str]:
        """The run's description in the recording (strings)."""
        return {"command": self.action_name, "goal": self.goal_text, "plant": episode.plant,
                "state": episode.state, "estimator": episode.estimator,
                "control_rate_hz": f"{1.0 / episode.control_period_s:g}",
                "physics_timestep_s": f"{episode.timestep_s:g}"}

    def _run(self, runner: EpisodeRunner, episode: Episode) -> int:
        try:
            result = runner.run()
        except RenderingUnavailableError as err:
            print(f"go2-wbc: --video: offscreen rendering is unavailable "
                  f"(MUJOCO_GL={os.environ.get('MUJOCO_GL', '')!r}): {err}. Install libosmesa6 "
                  "(apt-get install libosmesa6) or set MUJOCO_GL=egl", file=sys.stderr)
            return EXIT_UNAVAILABLE
        if result.status == UNAVAILABLE:
            print(f"go2-wbc: the '{self.action_name}' action is not served by this version "
                  f"(served: {', '.join(runner.loop.runner.server_names)})", file=sys.stderr)
            return EXIT_UNAVAILABLE
        code = self._finish(result, episode)
        self._write_outputs(runner, result, episode)
        self._keep_viewer_open(runner, code)
        return code

    def _finish(self, result: EpisodeResult, episode: Episode) -> int:
        """The result's line and the metrics; the exit code."""
        now_s = self.runner.loop.context.now_s
        if result.status == REJECTED:
            rejection = result.rejection
            self.result = {"status": REJECTED, "success": False, "message": rejection.message,
                           "rejection_code": rejection.code}
        elif result.wrapped is not None:
            status, message, returned = result.status, result.message, result.wrapped.result
            self.result = {"status": status, "success": result.succeeded, "message": message}
            text = f"[{now_s:7.3f} s] result: {status}"
            if hasattr(returned, "error_code"):
                self.result["error_code"] = returned.error_code
                text += f" (error_code {returned.error_code})"
            self.say(text + (f": {message}" if message else ""))
            if result.metrics is not None:
                self.say(metrics_text(result.metrics,
                                      raised=self.action_name == HIGH_FIVE_ACTION,
                                      estimated=episode.state == "estimate"))
        elif not result.interrupted:  # canceled, and no result came
            self.result = {"status": result.status, "success": False, "message": ""}
            self.say(f"[{now_s:7.3f} s] result: none ({result.status})")
        return exit_code(result)

    # -- what the runner tells -------------------------------------------------------------

    def goal_sending(self, runner: EpisodeRunner, now_s: float) -> None:
        if self.recording is not None:  # from the goal's sending on, as --log
            from sim.recording_hook import RecordingHook

            runner.loop.hooks.append(RecordingHook(
                self.recording, runner.loop, lambda: runner.phase, runner.episode.moving_leg))
        self.say(f"[{now_s:7.3f} s] {self.action_name}: sending goal ({self.goal_text})")

    def calibrated(self, report: Any) -> None:
        now_s = self.runner.loop.robot.time_s
        for line in report.describe().splitlines():
            self.say(f"[{now_s:7.3f} s] {line}")

    def goal_response(self, handle: ClientGoalHandle, now_s: float) -> None:
        if handle.accepted:
            self.say(f"[{now_s:7.3f} s] goal accepted")
            return
        rejection = handle.rejection
        self.say(f"[{now_s:7.3f} s] goal rejected (code {rejection.code}): {rejection.message}")

    def feedback(self, sample: FeedbackSample, message: Any) -> None:
        detail = ""
        if sample.joint_error_rad is not None:
            self.max_error = max(self.max_error, sample.joint_error_rad)
            if self.max_error > 0.0:
                detail = f"largest joint error so far {self.max_error:.4f} rad"
        self.printer.feedback(sample.t_s, sample.phase, sample.progress, detail)
        if self.recording is not None:
            self.recording.feedback(sample.phase, sample.progress, sample.t_s)

    def event(self, event: EpisodeEvent) -> None:
        if event.push is not None:
            push = event.push
            self.say(f"[{event.t_s:7.3f} s] push: {push.force_n:g} N at "
                     f"{push.direction_deg:g} deg for {push.duration_s:g} s")
            return
        self.say(f"[{event.t_s:7.3f} s] canceling the goal ({event.details['reason']})")

    def cancel_reply(self, response: Any, now_s: float) -> None:
        self.say(f"[{now_s:7.3f} s] cancel {'accepted' if response.accepted else 'refused'}: "
                 f"{response.message}")

    def viewer_unavailable(self, reason: str) -> None:
        print(f"go2-wbc: --viewer: {reason}; running headless", file=sys.stderr)

    def loop_state(self, text: str, now_s: float) -> None:
        self.say(f"[{now_s:7.3f} s] {text}")

    def viewer_closed(self, view: ViewerHook, *, unpaced: bool) -> None:
        how = ("was closed" if view.error is None else
               f"failed ({type(view.error).__name__}: {' '.join(str(view.error).split())})")
        self.say(f"[{view.closed_at_s:7.3f} s] viewer: the window {how}; the run goes on "
                 f"headless{', as fast as possible' if unpaced else ''}")

    # -- outputs ---------------------------------------------------------------------------

    def _write_outputs(self, runner: EpisodeRunner, result: EpisodeResult,
                       episode: Episode) -> None:
        args = self.args
        if runner.video is not None:
            self.say(f"wrote {args.video} ({runner.video.frames} frames at {args.fps} fps)")
        if args.report is not None and self.result is not None:
            report = self._report(runner, result, episode)
            args.report.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
            self.say(f"wrote {args.report}")
        if runner.recorder is not None and self.result is not None and (
                result.status != REJECTED):
            arrays = runner.recorder.arrays()
            if args.log is not None:
                np.savez_compressed(args.log, **arrays)
                self.say(f"wrote {args.log} ({len(arrays['t_s'])} ticks)")
            if args.plot is not None:
                write_plot(args.plot, arrays, title=f"{self.action_name} ({self.goal_text})",
                           caption=run_caption(episode))
                self.say(f"wrote {args.plot}")

    def _report(self, runner: EpisodeRunner, result: EpisodeResult,
                episode: Episode) -> dict[str, Any]:
        feedback = []
        for sample in result.feedback:
            entry = {"t_s": round(sample.t_s, 4), "phase": sample.phase,
                     "progress": round(sample.progress, 4)}
            if sample.joint_error_rad is not None:
                entry["max_joint_error_rad"] = round(sample.joint_error_rad, 5)
            feedback.append(entry)
        estimator = runner.loop.estimator
        return {
            "action": self.action_name,
            "goal": dataclasses.asdict(episode.goal),
            "start_pose": episode.start_pose,
            "plant": dataclasses.asdict(episode.plant_model),
            "state": {
                "source": episode.state,
                "estimator": episode.estimator if episode.state == "estimate" else None,
                "estimator_params": dict(episode.estimator_params),
                "sensors": episode.sensor_model.as_dict(),
                "sensor_seed": episode.sensor_seed,
                "estimator_config": (None if estimator is None
                                     else dataclasses.asdict(estimator.config)),
                "command_delay_s": episode.command_delay_s,
                "sensor_faults": [dataclasses.asdict(f) for f in episode.sensor_faults],
                "foot_calibration": (None if estimator is None
                                     else dataclasses.asdict(estimator.foot_calibration)),
                "calibration": (None if result.calibration is None
                                else result.calibration.as_dict()),
            },
            "control_rate_hz": self.args.control_rate,
            "physics_timestep_s": episode.timestep_s,
            "result": self.result,
            "phases": [{"phase": phase, "t_s": round(t_s, 4)} for t_s, phase in result.phases()],
            "events": [e.as_dict() for e in result.events],
            "feedback": feedback,
            "loop_modes": [t.as_dict() for t in runner.loop.fallback.log.transitions],
            "metrics": None if result.metrics is None else result.metrics.as_dict(),
            "wall_time_s": round(result.wall_s, 3),
        }

    def _keep_viewer_open(self, runner: EpisodeRunner, code: int) -> None:
        """--viewer: the window stays on the final state, paused, until its user closes it
        (not with --viewer-exit, after Ctrl-C, or when it has gone)."""
        view = runner.view
        if (view is None or self.args.viewer_exit or code == EXIT_INTERRUPTED
                or not view.is_open):
            return
        self.say(f"[{runner.loop.context.now_s:7.3f} s] viewer: paused on the final state; "
                 "close the window to exit (--viewer-exit closes it at the end)")
        with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C closes it too
            view.hold(runner.loop)

