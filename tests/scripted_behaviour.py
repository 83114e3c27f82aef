"""A scripted behaviour for tests and demos: runs N steps, unwinds over M steps, can fail on cue."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from actions.behaviour import Behaviour, StepResult
from actions.go2.go2_interfaces import HighFiveFeedback, HighFiveResult
from actions.goal_status import GoalStatus
from wbc.core.errors import ConfigurationError

_METHODS = ("start", "step", "cancel", "abort_result")


class ScriptedBehaviour(Behaviour[Any, Any, Any]):
    """A behaviour that needs no robot: it counts steps and ends when told to.

    It works with any action whose result has ``success``/``message`` fields and whose
    feedback has ``phase``/``progress`` fields (HighFive, Stand, Sit).

    Args:
        steps: Steps until it ends with ``end_status`` (the step count includes the first
            step, on the start tick); ``None`` never ends by itself.
        unwind_steps: Steps after :meth:`cancel` until it ends CANCELED; ``None`` never
            finishes the unwind (the runner's unwind timeout then aborts it).
        end_status: ``SUCCEEDED`` or ``ABORTED``.
        fail_in: Name of a method (``"start"``, ``"step"``, ``"cancel"``,
            ``"abort_result"``) that raises ``RuntimeError("<method> failed")``.
        result_type: Result class to build.
        feedback_type: Feedback class to build.

    Attributes:
        calls: Every call received, as ``(method, now_s, detail)``; ``now_s`` is ``None``
            for ``abort_result``, ``detail`` is the cancel reason or abort message.
    """

    def __init__(
        self,
        *,
        steps: int | None = 3,
        unwind_steps: int | None = 1,
        end_status: GoalStatus = GoalStatus.SUCCEEDED,
        fail_in: str | None = None,
        result_type: type = HighFiveResult,
        feedback_type: type = HighFiveFeedback,
    ) -> None:
        for name, value in (("steps", steps), ("unwind_steps", unwind_steps)):
            if value is not None and (not isinstance(value, int) or value < 1):
                raise ConfigurationError(f"{name} must be None or an int >= 1; received {value!r}")
        if end_status not in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED):
            raise ConfigurationError(
                f"end_status must be GoalStatus.SUCCEEDED or ABORTED; received {end_status!r}"
            )
        if fail_in is not None and fail_in not in _METHODS:
            raise ConfigurationError(
                f"fail_in must be None or one of {', '.join(_METHODS)}; received {fail_in!r}"
            )
        self._steps = steps
        self._unwind_steps = unwind_steps
        self._end_status = end_status
        self._fail_in = fail_in
        self._result_type = result_type
        self._feedback_type = feedback_type
        self._step_count = 0
        self._unwind_count = 0
        self._cancel_reason: str | None = None
        self.calls: list[tuple[str, float | None, str]] = []

    def start(self, goal: Any, now_s: float) -> None:
        """Record the call."""
        self._record("start", now_s, "")

    def step(self, now_s: float) -> StepResult[Any, Any]:
        """Count a step; end when the script says so."""
        self._record("step", now_s, "")
        if self._cancel_reason is not None:
            self._unwind_count += 1
            if self._unwind_steps is not None and self._unwind_count >= self._unwind_steps:
                return StepResult.canceled(
                    self._result_type(success=False, message=f"canceled: {self._cancel_reason}")
                )
            return StepResult.running(self._feedback("unwinding"))
        self._step_count += 1
        if self._steps is not None and self._step_count >= self._steps:
            result = self._result_type(
                success=self._end_status == GoalStatus.SUCCEEDED,
                message=f"{self._end_status.name.lower()} after {self._step_count} steps",
            )
            return StepResult(self._feedback("complete"), self._end_status, result)
        return StepResult.running(self._feedback("running"))

    def cancel(self, now_s: float, reason: str) -> None:
        """Record the call and begin the unwind."""
        self._record("cancel", now_s, reason)
        self._cancel_reason = reason

    def abort_result(self, message: str) -> Any:
        """A failed result carrying ``message``."""
        self._record("abort_result", None, message)
        return self._result_type(success=False, message=message)

    def _feedback(self, phase: str) -> Any:
        progress = 0.0 if self._steps is None else min(1.0, self._step_count / self._steps)
        return self._feedback_type(phase=phase, progress=progress)

    def _record(self, method: str, now_s: float | None, detail: str) -> None:
        self.calls.append((method, now_s, detail))
        if method == self._fail_in:
            raise RuntimeError(f"{method} failed")


def scripted_factory(
    made: list[ScriptedBehaviour], **kwargs: Any
) -> Callable[[], ScriptedBehaviour]:
    """A behaviour factory that appends every behaviour it makes to ``made``.

    Args:
        made: Receives each new :class:`ScriptedBehaviour`, in order.
        **kwargs: Passed to :class:`ScriptedBehaviour`.
    """

    def factory() -> ScriptedBehaviour:
        behaviour = ScriptedBehaviour(**kwargs)
        made.append(behaviour)
        return behaviour

    return factory
