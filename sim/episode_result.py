"""What an episode tells as it runs (:class:`EpisodeListener`), and what it did (the result)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from actions.responses import WrappedResult
    from sim.control_loop import ControlLoop
    from sim.disturbances import Push
    from sim.episode_metrics import EpisodeSummary

#: :attr:`EpisodeResult.status` beyond a goal's terminal statuses (SUCCEEDED, CANCELED,
#: ABORTED): the server rejected the goal; the action is not served; no result came (within
#: the slack after a cancel); interrupted before the goal was accepted; no goal was sent.
REJECTED, UNAVAILABLE, NO_RESULT, INTERRUPTED, NO_GOAL = (
    "REJECTED", "UNAVAILABLE", "NO_RESULT", "INTERRUPTED", "NO_GOAL")


@dataclass
class EpisodeEvent:
    """Something that happened to the goal, at a simulated time.

    Attributes:
        t_s: Sim time [s].
        event: ``accepted``, ``cancel_requested``, ``timeout``, ``interrupted``, ``push``
            or ``result``.
        details: What the report says of it (``reason``, ``status``, a push's ``force_n``).
        push: The push applied (``push`` events).
    """

    t_s: float
    event: str
    details: dict[str, Any] = field(default_factory=dict)
    push: Push | None = field(default=None, repr=False, compare=False)

    def as_dict(self) -> dict[str, Any]:
        """Plain values, JSON-ready (time rounded to 0.1 ms)."""
        return {"t_s": round(self.t_s, 4), "event": self.event, **self.details}


@dataclass(frozen=True)
class FeedbackSample:
    """One feedback message as the runner reads it.

    Attributes:
        t_s: Sim time [s] it was received.
        phase: The goal's phase (a trajectory's: ``starting``, ``following``, ``settling``).
        progress: Progress in [0, 1].
        joint_error_rad: A trajectory's largest joint error in the message [rad] (``None``
            for the other actions).
    """

    t_s: float
    phase: str
    progress: float
    joint_error_rad: float | None = None


def feedback_view(feedback: Any, trajectory_end_s: float | None
                  ) -> tuple[str, float, float | None]:
    """``(phase, progress 0..1, largest joint error [rad] or None)`` of a feedback message.

    Args:
        feedback: The action's feedback message.
        trajectory_end_s: A trajectory's last point's time [s] (its progress's end).
    """
    if hasattr(feedback, "phase"):
        return feedback.phase, float(feedback.progress), None
    # FollowJointTrajectory feedback has no phase field: the phase shown and the progress
    # are read from the trajectory time reached, desired.time_from_start.
    desired_s = feedback.desired.time_from_start.to_seconds()
    progress = min(1.0, desired_s / trajectory_end_s) if trajectory_end_s else 1.0
    error = max((abs(e) for e in feedback.error.positions), default=0.0)
    if desired_s <= 0.0:
        phase = "starting"  # the leg is being released, or the start stamp is ahead
    elif trajectory_end_s is None or desired_s <= trajectory_end_s:
        phase = "following"
    else:
        phase = "settling"  # past the last point's time: the goal tolerance is checked
    return phase, progress, error


class EpisodeListener:
    """What a running episode tells, as it happens; every method does nothing here."""

    def goal_sending(self, runner: Any, now_s: float) -> None:
        """The goal is about to be sent, at sim time ``now_s`` [s] (after the settle), by
        ``runner`` (a :class:`sim.episode_runner.EpisodeRunner`)."""

    def goal_response(self, handle: ClientGoalHandle, now_s: float) -> None:
        """The server accepted or rejected the goal (``handle.accepted``, ``rejection``)."""

    def feedback(self, sample: FeedbackSample, message: Any) -> None:
        """A feedback message (the action's ``FeedbackMessage``), as read."""

    def event(self, event: EpisodeEvent) -> None:
        """A cancel requested (``cancel_requested``, ``timeout``, ``interrupted``) or a push."""

    def calibrated(self, report: Any) -> None:
        """The standing calibration ended (its
        :class:`actions.robot.foot_calibration.CalibrationReport`), before the goal."""

    def cancel_reply(self, response: Any, now_s: float) -> None:
        """The server's reply to a cancel request (``accepted``, ``message``)."""

    def viewer_unavailable(self, reason: str) -> None:
        """The viewer asked for cannot open; the episode runs headless."""

    def viewer_closed(self, view: Any, *, unpaced: bool) -> None:
        """The viewer's window went mid-run (``view``, a :class:`sim.viewer.ViewerHook`;
        ``unpaced``: the pacing stopped with it)."""

    def loop_state(self, text: str, now_s: float) -> None:
        """What the loop says of its state before the goal is sent, at sim time ``now_s``
        [s]: why it is not controlling yet (and then that it is), or how the estimator
        started."""


@dataclass
class EpisodeResult:
    """How an episode ended, what it went through, and what it measured.

    Attributes:
        status: The goal's terminal status's name (``SUCCEEDED``, ``CANCELED``,
            ``ABORTED``), or :data:`REJECTED`, :data:`UNAVAILABLE`, :data:`NO_RESULT`,
            :data:`INTERRUPTED`, :data:`NO_GOAL`.
        loop: The control loop, in the state the episode ended in.
        wrapped: The goal's status and result message (``None`` without a result).
        rejection: The server's rejection (its ``code`` and ``message``) when rejected.
        goal_id: The goal's id once accepted.
        feedback: Every feedback message, read.
        events: The goal's events, in order.
        metrics: The episode measured on the simulator's truth from the goal's sending
            (``None`` unless asked for).
        interrupted: Ctrl-C arrived while the goal ran (the goal was canceled).
        sent_s: Sim time [s] the goal was sent (the end of the settle).
        sim_s: Sim time [s] run from the sending to the result (``after_s`` not included).
        ticks: Control ticks from the sending to the result.
        wall_s: Wall time [s] from the sending to the end (``after_s`` included).
        cpu_s: The process's CPU time [s] over the same span.
        overhead_s: Wall time [s] of it spent measuring, recording, rendering, in the viewer
            and sleeping: left out of the metrics' real-time factor.
        calibration: The standing calibration's report
            (:class:`actions.robot.foot_calibration.CalibrationReport`; ``None`` without one).
    """

    status: str
    loop: ControlLoop = field(repr=False)
    wrapped: WrappedResult | None = None
    rejection: Any = None
    goal_id: Any = None
    feedback: list[FeedbackSample] = field(default_factory=list)
    events: list[EpisodeEvent] = field(default_factory=list)
    metrics: EpisodeSummary | None = None
    interrupted: bool = False
    sent_s: float = 0.0
    sim_s: float = 0.0
    ticks: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0
    overhead_s: float = 0.0
    calibration: Any = None

    @property
    def message(self) -> str:
        """The result's message (a trajectory's ``error_string``), or the rejection's."""
        if self.wrapped is not None:
            result = self.wrapped.result
            return getattr(result, "message", None) or getattr(result, "error_string", "")
        return "" if self.rejection is None else self.rejection.message

    @property
    def succeeded(self) -> bool:
        """SUCCEEDED, and the result says so too (``success``, or ``error_code`` 0)."""
        if self.wrapped is None or self.status != "SUCCEEDED":
            return False
        result = self.wrapped.result
        return bool(getattr(result, "success", getattr(result, "error_code", 0) == 0))

    def phases(self) -> list[tuple[float, str]]:
        """``(sim time [s], phase)`` of each change of phase in the feedback."""
        changes: list[tuple[float, str]] = []
        for sample in self.feedback:
            if not changes or changes[-1][1] != sample.phase:
                changes.append((sample.t_s, sample.phase))
        return changes
