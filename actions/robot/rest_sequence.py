"""Start and stop a robot's control loop safely: stand a robot that is down, and bring it to
rest before the controller exits. A filter of the loop's tick
(:class:`~actions.robot.robot_tick.TickFilter`): from ``DAMPING`` on, its damping command
replaces the tick's decision.

Stopping (:meth:`RestSequence.request_stop`), in phases, one control tick at a time:

1. ``UNWINDING``: every running goal is canceled and unwinds as its server defines (a high
   five puts the foot down). A goal that arrives meanwhile is canceled too.
2. ``SITTING``: a ``sit`` goal lowers the body to the lying pose (the robot's sit goal,
   :meth:`~actions.robot.loop_behaviours.LoopBehaviours.sit_goal`).
3. ``DAMPING``: the action runner is shut down (new goals are rejected) and the motors get a
   pure damping command (no stiffness, no torque) for ``damp_s``.
4. ``DONE``: the loop may exit.

A second stop request skips to ``DAMPING``; so does a stop that has not reached ``DAMPING``
within ``timeout_s`` (a goal that will not end, a sit that cannot run).
"""

from __future__ import annotations

import enum
import math
from concurrent.futures import Future
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from actions.goal_status import GoalStatus
from actions.robot.state_fallback import send_stand
from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real
from wbc.model.description import JOINT_NAMES
from wbc.robot_io.motor_command import MotorCommand

if TYPE_CHECKING:
    from actions.client_goal_handle import ClientGoalHandle
    from actions.robot.robot_loop import RobotLoop


class Phase(enum.IntEnum):
    """Where a loop is between its start and its exit."""

    RUNNING = 0
    UNWINDING = 1
    SITTING = 2
    DAMPING = 3
    DONE = 4


@dataclass(frozen=True)
class RestSettings:
    """How a loop starts and comes to rest.

    Attributes:
        stand_on_start: Stand the robot up first if its base is below its standing height
            (:attr:`~actions.robot.loop_behaviours.LoopBehaviours.standing_height_m`: the
            GO2's :data:`~actions.go2.robot_context.STANDING_HEIGHT_M`).
        stand_s: Duration [s] of that stand.
        sit_s: Duration [s] of the sit when stopping.
        damping_kd: Joint damping [N m s/rad] of the final command (no stiffness, no torque).
        damp_s: How long [s] the damping command is sent before the loop exits.
        timeout_s: Longest [s] from a stop request to ``DAMPING`` (a goal's unwind, then the
            sit).
    """

    stand_on_start: bool = True
    stand_s: float = 2.0
    sit_s: float = 1.5
    damping_kd: float = 5.0
    damp_s: float = 0.5
    timeout_s: float = 8.0

    def __post_init__(self) -> None:
        for name in ("stand_s", "sit_s", "damping_kd", "damp_s", "timeout_s"):
            value = getattr(self, name)
            if not is_finite_real(value) or value < 0.0:
                raise ConfigurationError(
                    f"{name}: expected a finite number >= 0, received {value!r}")


def damping_command(kd: float) -> MotorCommand:
    """Pure joint damping (description order): ``kp = 0``, ``kd``, no torque, no targets."""
    zeros = np.zeros(len(JOINT_NAMES))
    return MotorCommand(q_des=zeros, dq_des=zeros, kp=zeros, kd=np.full(len(JOINT_NAMES), kd),
                        tau_ff=zeros)


class RestSequence:
    """The start-up stand and the stop phases of one loop (see the module doc).

    Pass it to the loop's tick as a filter (:meth:`sensed` steps it after sensing, before
    the runner's tick), or call :meth:`step` on the loop's thread at the start of every tick;
    :meth:`request_stop` from anywhere (a signal handler included: it only counts).
    """

    def __init__(self, loop: RobotLoop, settings: RestSettings | None = None) -> None:
        self.loop = loop
        self.settings = settings or RestSettings()
        self.phase = Phase.RUNNING
        #: Why the loop is stopping ('' while running).
        self.stop_reason = ""
        self._requests = 0
        self._reasons: list[str] = []
        self._stop_s = math.nan
        self._damp_s = math.nan
        self._canceled: set[str] = set()
        self._notes: list[str] = []
        self._sit: Future[ClientGoalHandle] | None = None
        #: The start-up stand's goal handle future (``None`` if the robot was standing).
        self.stand: Future[ClientGoalHandle] | None = None
        self.damping = damping_command(self.settings.damping_kd)

    def stand_if_down(self) -> bool:
        """Send a ``stand`` goal if the robot's base is below standing height (once); whether
        it was sent now."""
        if (self.stand is not None or not self.settings.stand_on_start
                or self.loop.context.goal_refusal  # not controlling: the loop stands it
                or self.loop.context.q[2] >= self.loop.behaviours.standing_height_m):
            return False
        self.stand = send_stand(self.loop, self.settings.stand_s)
        return True

    def request_stop(self, reason: str) -> None:
        """Ask the loop to come to rest (a second request: damp now). Any thread."""
        self._reasons.append(reason)
        self._requests += 1

    def sensed(self, now_s: float, fresh: bool) -> MotorCommand | None:
        """The tick's filter: :meth:`step`; from ``DAMPING`` on, the damping command that
        replaces the tick's decision (``None`` before: the loop decides)."""
        return self.damping if self.step(now_s) >= Phase.DAMPING else None

    def stale(self, now_s: float) -> str:
        """The tick's filter: the rest sequence never finds the state stale ('')."""
        return ""

    def step(self, now_s: float) -> Phase:
        """Advance the phases at robot time ``now_s`` [s]; return the current one."""
        requests = self._requests
        if requests and self.phase is Phase.RUNNING:
            self.stop_reason = self._reasons[0]
            self._stop_s = now_s
            self.phase = Phase.UNWINDING
        if requests > 1 and self.phase < Phase.DAMPING:
            self._enter_damping(now_s, f"second stop request ({self._reasons[1]})")
        if self.phase in (Phase.UNWINDING, Phase.SITTING) and (
                now_s - self._stop_s > self.settings.timeout_s):
            self._enter_damping(now_s, f"not at rest within {self.settings.timeout_s:g} s")
        if self.phase is Phase.UNWINDING:
            self._unwind()
        if self.phase is Phase.SITTING:
            self._sitting(now_s)
        if self.phase is Phase.DAMPING and now_s - self._damp_s >= self.settings.damp_s:
            self.phase = Phase.DONE
        return self.phase

    @property
    def notes(self) -> list[str]:
        """What the stop did, in order (for the exit summary)."""
        return list(self._notes)

    def _note(self, text: str) -> None:
        self._notes.append(text)

    def _unwind(self) -> None:
        goals = self.loop.runner.active_goals()
        for record in goals:
            if record.goal_id not in self._canceled:
                self._canceled.add(record.goal_id)
                self._note(f"canceled {record.label}")
                self.loop.runner.submit_cancel(record)
        if not goals:
            action, goal = self.loop.behaviours.sit_goal(self.settings.sit_s)
            self._sit = self.loop.client(action).send_goal_async(goal)
            self.phase = Phase.SITTING

    def _sitting(self, now_s: float) -> None:
        future = self._sit
        if future is None or not future.done():
            return
        handle = future.result()
        if not handle.accepted:
            refusal = self.loop.context.goal_refusal
            if refusal:  # no trustworthy state: no sit is possible
                self._note(f"sit refused ({refusal})")
                self._enter_damping(now_s, "not at rest: the robot could not be sat down")
                return
            self.phase = Phase.UNWINDING  # a goal came first: cancel it, then sit again
            self._unwind()
            return
        status = handle.status
        if status.is_terminal:
            height = float(self.loop.context.q[2])
            if status is GoalStatus.SUCCEEDED:
                self._note("sit ended SUCCEEDED")
                self._enter_damping(now_s, "at rest")
                return
            result = handle.get_result_async()
            message = result.result().result.message if result.done() else ""
            self._note(f"sit ended {status.name}" + (f": {message}" if message else ""))
            self._enter_damping(now_s, f"not at rest: base at {height:.2f} m")

    def _enter_damping(self, now_s: float, why: str) -> None:
        self._note(f"damping ({why})")
        self.phase = Phase.DAMPING
        self._damp_s = now_s
        self.loop.runner.shutdown(now_s)
