"""The interface a behaviour implements to run one goal, tick by tick (ROS 2: execute callback).

Where rclpy runs an ``execute_callback`` in its own thread, here a behaviour is a small state
machine stepped on the control tick, so a whole run is deterministic in simulated time.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Generic, TypeVar

from actions.goal_status import TERMINAL_STATUSES, GoalStatus
from wbc.core.errors import ConfigurationError

GoalT = TypeVar("GoalT")
ResultT = TypeVar("ResultT")
FeedbackT = TypeVar("FeedbackT")


@dataclass(frozen=True)
class StepResult(Generic[ResultT, FeedbackT]):
    """What one :meth:`Behaviour.step` reports.

    Attributes:
        feedback: Feedback to publish on this tick, or ``None``.
        status: ``None`` while the goal goes on; ``SUCCEEDED``, ``ABORTED`` or ``CANCELED``
            when it has ended on this tick.
        result: The action's result message; given exactly when ``status`` is.

    Use the constructors: ``StepResult.running(fb)``, ``StepResult.succeeded(result)``,
    ``StepResult.aborted(result)``, ``StepResult.canceled(result)``.
    """

    feedback: FeedbackT | None = None
    status: GoalStatus | None = None
    result: ResultT | None = None

    def __post_init__(self) -> None:
        if self.status is not None and self.status not in TERMINAL_STATUSES:
            valid = ", ".join(status.name for status in sorted(TERMINAL_STATUSES))
            raise ConfigurationError(
                f"StepResult.status must be None or one of {valid}; received {self.status!r}"
            )
        if (self.status is None) != (self.result is None):
            raise ConfigurationError(
                "StepResult needs a result exactly when it has a terminal status; received "
                f"status={self.status!r}, result={self.result!r}"
            )

    @classmethod
    def running(cls, feedback: FeedbackT | None = None) -> StepResult[ResultT, FeedbackT]:
        """The goal goes on; optionally publish ``feedback``."""
        if feedback is None and cls is StepResult:
            return _GOES_ON  # most ticks: one shared instance (it is frozen)
        return cls(feedback=feedback)

    @classmethod
    def succeeded(
        cls, result: ResultT, feedback: FeedbackT | None = None
    ) -> StepResult[ResultT, FeedbackT]:
        """The goal reached its aim (only legal while EXECUTING)."""
        return cls(feedback=feedback, status=GoalStatus.SUCCEEDED, result=result)

    @classmethod
    def aborted(
        cls, result: ResultT, feedback: FeedbackT | None = None
    ) -> StepResult[ResultT, FeedbackT]:
        """The goal failed (legal while EXECUTING or CANCELING)."""
        return cls(feedback=feedback, status=GoalStatus.ABORTED, result=result)

    @classmethod
    def canceled(
        cls, result: ResultT, feedback: FeedbackT | None = None
    ) -> StepResult[ResultT, FeedbackT]:
        """The unwind after :meth:`Behaviour.cancel` is complete (only legal while CANCELING)."""
        return cls(feedback=feedback, status=GoalStatus.CANCELED, result=result)

    @property
    def done(self) -> bool:
        """Whether the goal ended on this step."""
        return self.status is not None


_GOES_ON: StepResult = StepResult()


class Behaviour(ABC, Generic[GoalT, ResultT, FeedbackT]):
    """Runs one accepted goal. The server's factory makes a fresh instance per accepted goal.

    Every method is called on the thread that ticks the runner, never concurrently, in this
    order:

    1. :meth:`start` once, on the tick the goal becomes EXECUTING; :meth:`step` follows on
       the same tick.
    2. :meth:`step` once per tick while the goal is EXECUTING or CANCELING, until it returns
       a terminal :class:`StepResult`.
    3. :meth:`cancel` at most once, on the tick a cancel is acknowledged (the goal is then
       CANCELING), before that tick's step. The behaviour then runs a bounded unwind in its
       steps and ends with ``StepResult.canceled(...)`` (or ``aborted``). It must finish
       within the server's ``max_unwind_s`` or the runner aborts it. On shutdown, ``cancel``
       is called and no step follows: the runner ends the goal itself.
    4. :meth:`abort_result` whenever the runner must end the goal without the behaviour's
       own result.

    A goal that never started (cancelled, preempted or shut down while ACCEPTED) gets no
    ``start``, ``step`` or ``cancel``, only ``abort_result``.

    Any exception raised by these methods ends the goal ABORTED with the exception's text;
    the runner stays usable. Returning a wrong type (not a ``StepResult``, a feedback or
    result of another action) also aborts the goal, with a message naming the expected type.
    """

    @abstractmethod
    def start(self, goal: GoalT, now_s: float) -> None:
        """Begin executing ``goal`` at simulated time ``now_s`` [s]."""

    @abstractmethod
    def step(self, now_s: float) -> StepResult[ResultT, FeedbackT]:
        """Advance by one control tick at ``now_s`` [s] and report feedback and/or the end.

        While the goal is EXECUTING it may end ``SUCCEEDED`` or ``ABORTED``; while it is
        CANCELING (after :meth:`cancel`) it may end ``CANCELED`` or ``ABORTED``. Any other
        end aborts the goal with a message naming the legal ones.
        """

    @abstractmethod
    def cancel(self, now_s: float, reason: str) -> None:
        """Begin the unwind at ``now_s`` [s].

        Args:
            now_s: Simulated time [s].
            reason: ``"canceled by client request"``, ``"preempted by goal <id> (<action
                name>)"`` or ``"runner shut down at t=<now_s> s"``.
        """

    @abstractmethod
    def abort_result(self, message: str) -> ResultT:
        """The result message for a goal the framework ends, carrying ``message``.

        Used when the goal never ran (canceled, preempted or shut down while ACCEPTED), was
        preempted, timed out in its unwind, or when a behaviour method raised.
        """
