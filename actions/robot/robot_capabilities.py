"""What a robot may offer beyond the :class:`~actions.robot.robot_interface.RobotInterface`,
declared as protocols: the robot loop asks ``isinstance(robot, StateWaiting)``; it never
looks a member up by name to find out what a robot can do.

A robot offers a capability by having its members (the protocols are structural): a
:class:`~actions.robot.dds_robot.DdsRobot` has them all; a simulated robot none. Each
capability is looked up once, when the loop (or its log) is built, not every tick: an
``isinstance`` against a protocol costs microseconds.

- :class:`StateWaiting`: it can wait for its next state (a wall-clock loop aligns its ticks
  to the states' arrival).
- :class:`CountsSkips`: its ``counters.ticks_skipped`` counts the states no read took.
- :class:`StalenessLimited`: it knows how long without a state is too long
  (``stale_after_s``, from the rate it measured).
- :class:`DescribesStream`: it says what its stream brought that was not new
  (``stale_reason()``), for the fallback's reason.
- :class:`AnswersTicks`: it knows the robot tick of the state its next command answers.
- :class:`ReportsStats`: it has figures for a run's report (``stats()``).
- :class:`AppliesCommandAtOnce`: it applies a command within the call and keeps nothing of
  it, so the loop hands it the controller's command without a copy.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

if TYPE_CHECKING:
    from wbc.robot_io.motor_command import MotorCommand


@runtime_checkable
class StateWaiting(Protocol):
    """A robot that can wait for its next state."""

    def wait_for_new_state(self, timeout_s: float) -> bool:
        """Wait at most ``timeout_s`` [s] for a state no read has taken; whether one is there."""


class SkipCounters(Protocol):
    """The counter :class:`CountsSkips` keeps."""

    #: Robot ticks that no read took (two states came within one read: the older skipped).
    ticks_skipped: int


@runtime_checkable
class CountsSkips(Protocol):
    """A robot that counts the states no read took."""

    @property
    def counters(self) -> SkipCounters:
        """Its counters (``ticks_skipped``)."""


@runtime_checkable
class StalenessLimited(Protocol):
    """A robot that knows how long without a new state is too long."""

    @property
    def stale_after_s(self) -> float:
        """The limit [s] (a :class:`~actions.robot.dds_robot.DdsRobot`'s: from its rate)."""


@runtime_checkable
class DescribesStream(Protocol):
    """A robot that says what its stream brought that was not new."""

    def stale_reason(self) -> str:
        """States that keep arriving but never change, dropped frames ('' when nothing)."""


@runtime_checkable
class AnswersTicks(Protocol):
    """A robot whose commands answer a numbered state."""

    @property
    def answer_tick(self) -> int:
        """The robot tick of the state the next command answers."""


@runtime_checkable
class ReportsStats(Protocol):
    """A robot with figures for a run's report."""

    def stats(self) -> dict[str, Any]:
        """Its counters and figures, JSON-ready."""


@runtime_checkable
class AppliesCommandAtOnce(Protocol):
    """A robot that applies a command within the call and keeps no reference to it (a
    simulator's drivers read its arrays once, then step): :class:`~actions.MappedRobot`
    hands it the controller's command itself, where any other robot gets a copy it may
    keep (a delay queue, a wire's send thread)."""

    def apply_command(self, command: MotorCommand) -> None:
        """:meth:`~actions.robot.robot_interface.RobotInterface.write_command`, the
        command's arrays read before it returns."""
