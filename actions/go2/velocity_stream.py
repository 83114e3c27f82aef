"""The streaming velocity command (``cmd_vel``): the latest velocity any thread gave, and the
walk it starts and steers, stopped by a timeout in the loop's own clock.

A command that is not zero while the robot is idle sends a ``walk`` goal (the stream's own:
:meth:`VelocityStream.claim` tells the Walk behaviour so), which then reads every newer command
on its control tick: it steers with a command that is not zero, stops on four feet on a zero
command or when no command came for the command's ``timeout_s`` of robot time (simulated time
in simulation), stamped by the tick that first sees the command. Going through the action
runner keeps one motion at a time: while any other goal runs the stream's walk is refused (and
:attr:`VelocityStream.refusal` says why), and while the stream walks, other goals are refused
with the reason.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real
from wbc.locomotion.gait import VelocityLimits

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from actions.go2.go2_interfaces import WalkGoal

#: Default time [s] after the last command at which a streamed walk stops.
DEFAULT_TIMEOUT_S = 0.5
#: Longest timeout [s] a command may carry.
MAX_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class VelocityCommand:
    """One streamed command.

    Attributes:
        forward_mps, lateral_mps: Velocity in the base's heading frame [m/s].
        yaw_rate_radps: Turning rate [rad/s].
        timeout_s: Robot time [s] after which, with no newer command, the walk stops.
        sequence: Its number in the stream (1 for the first).
    """

    forward_mps: float
    lateral_mps: float
    yaw_rate_radps: float
    timeout_s: float
    sequence: int

    @property
    def is_zero(self) -> bool:
        """Every component is zero: a stop."""
        return self.forward_mps == 0.0 and self.lateral_mps == 0.0 and self.yaw_rate_radps == 0.0


class VelocityStream:
    """The latest velocity command of one robot, and the walk goals it sends.

    :meth:`command` may be called from any thread (a teleop's, a DDS reader's, a ROS 2
    callback); the walk behaviour reads :meth:`latest` on the control tick.

    Args:
        limits: What a command may ask for (default: the walking motion's,
            :class:`wbc.locomotion.gait.VelocityLimits`).
        timeout_s: Default timeout [s] of a command.
    """

    def __init__(self, limits: VelocityLimits | None = None, *,
                 timeout_s: float = DEFAULT_TIMEOUT_S) -> None:
        _check_timeout(timeout_s)
        self.limits = limits if limits is not None else VelocityLimits()
        self.timeout_s = float(timeout_s)
        self._lock = threading.Lock()
        self._latest: VelocityCommand | None = None
        self._send: Callable[[WalkGoal], Future[ClientGoalHandle]] | None = None
        self._make_goal: Callable[[VelocityCommand], WalkGoal] | None = None
        self._walking = False  # a stream goal is pending or running
        self._claim: WalkGoal | None = None  # the goal sent and not yet started
        self._stop_sequence = 0  # the command a walk of the stream stopped at
        self._refusal = ""
        #: Commands received, and those that could not start a walk (refused goals).
        self.received = 0
        self.refused = 0

    def attach(self, send: Callable[[WalkGoal], Future[ClientGoalHandle]],
               make_goal: Callable[[VelocityCommand], WalkGoal]) -> None:
        """Where walk goals go (``ActionClient(runner, "walk").send_goal_async``) and how one
        is made from a command."""
        self._send, self._make_goal = send, make_goal

    def command(self, forward_mps: float, lateral_mps: float, yaw_rate_radps: float, *,
                timeout_s: float | None = None) -> None:
        """Command a velocity (base heading frame); any thread.

        Args:
            forward_mps, lateral_mps: [m/s]; yaw_rate_radps: [rad/s], counter-clockwise.
            timeout_s: Robot time [s] after which the walk stops unless a newer command came
                (default :attr:`timeout_s`).

        Raises:
            ConfigurationError: A component beyond the limits or not finite, or a timeout
                outside (0, 10] s: the message names the field, the value and the range.
        """
        problem = self.limits.problem(forward_mps, lateral_mps, yaw_rate_radps)
        if problem:
            raise ConfigurationError(f"velocity command: {problem}")
        timeout = self.timeout_s if timeout_s is None else timeout_s
        _check_timeout(timeout)
        with self._lock:
            self.received += 1
            latest = self._latest = VelocityCommand(
                float(forward_mps), float(lateral_mps), float(yaw_rate_radps), float(timeout),
                self.received)
            start = not latest.is_zero and not self._walking and self._send is not None
            if start:
                self._walking = True
        if start:
            self._start(latest)

    def latest(self) -> VelocityCommand | None:
        """The newest command (``None`` before the first)."""
        return self._latest

    @property
    def refusal(self) -> str:
        """Why the last walk the stream tried to start was refused ('' when it was not)."""
        return self._refusal

    @property
    def walking(self) -> bool:
        """A walk of the stream is pending or running."""
        return self._walking

    def claim(self, goal: Any) -> bool:
        """Whether ``goal``, starting now, is the stream's walk (then the behaviour follows
        the stream); called by the Walk behaviour's start, on the control tick."""
        with self._lock:
            mine = self._claim is not None and goal == self._claim
            if mine:
                self._claim = None
            return mine

    def stopped_at(self, command: VelocityCommand | None) -> None:
        """The stream's walk stopped at ``command`` (its timeout or a zero): a newer command
        that is not zero starts the next walk once this one has ended."""
        self._stop_sequence = 0 if command is None else command.sequence

    def _start(self, command: VelocityCommand) -> None:
        send, make_goal = self._send, self._make_goal
        if send is None or make_goal is None:  # not attached: commands start nothing
            self._walking = False
            return
        goal = make_goal(command)
        with self._lock:
            self._claim = goal
        send(goal).add_done_callback(self._answered)

    def _answered(self, future: Future[ClientGoalHandle]) -> None:
        handle = future.result()
        if not handle.accepted:
            with self._lock:
                self._walking, self._claim = False, None
                self.refused += 1
            rejection = handle.rejection
            self._refusal = rejection.message if rejection is not None else "rejected"
            return
        self._refusal = ""
        handle.get_result_async().add_done_callback(lambda _: self._ended())

    def _ended(self) -> None:
        """The stream's walk ended: start the next one if a newer command asks to move."""
        with self._lock:
            self._walking, self._claim = False, None
            latest = self._latest
            if latest is None or latest.is_zero or latest.sequence <= self._stop_sequence:
                return
            self._walking = True
        self._start(latest)


def _check_timeout(timeout_s: Any) -> None:
    if isinstance(timeout_s, bool) or not is_finite_real(timeout_s) or not (
            0.0 < timeout_s <= MAX_TIMEOUT_S):
        raise ConfigurationError(
            f"timeout_s: expected a time in (0, {MAX_TIMEOUT_S:g}] s, received {timeout_s!r}")
