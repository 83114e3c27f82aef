"""What the robot loop sends while its state cannot be trusted, and how it takes control back.

The loop is in one :class:`LoopMode` at a time:

- ``WAITING``: no sample yet that can start the state estimator (none, or NaN joints or
  gyroscope, or no attitude): pure joint damping, goals refused with the reason.
- ``CONTROLLING``: the controller's command.
- ``FALLBACK``: the state is not trustworthy (the estimator has had no trustworthy sample for
  longer than its ``trust_timeout_s``, or a wall-clock loop's watchdog found no fresh state
  for ``stale_after_s``). The running goal ends ABORTED with the reason, new goals are
  refused, and the motors get :func:`decaying_damping`: the last good feed-forward torques
  ramp linearly to zero over ``decay_s``, with ``kp = 0`` and joint damping throughout
  (``damping_kd`` on the legs in stance when the state was lost, ``swing_damping_kd`` on a
  leg in the air); after ``decay_s`` the command is pure damping (``tau_ff = 0``, ``kp = 0``,
  ``dq_des = 0``): each driver applies ``-kd * dq`` from its own encoder, which needs no
  state from the loop. Nothing holds the robot up: it sinks slowly onto its feet and belly.
- ``RECOVERING``: fresh trustworthy state is back (the estimator started again from it,
  :meth:`wbc.estimation.state_estimator.EstimatorBase.update`); the controller is reset to
  it and a ``stand`` goal (the rest sequence's stand-up, :func:`send_stand`) brings the
  robot to standing from wherever it is. Other goals are refused until it SUCCEEDS; then
  ``CONTROLLING``.

Why a decay and not a cut: a step from up to 10 N m of held torque to none jolts the legs;
a ramp of ``decay_s`` = 0.1 s is 50 ticks at 500 Hz. Why not longer: the held torques were
computed for a state that is no longer known (a high five's raised leg, a body leaning on
three feet), and held for 55 s they pushed a simulated GO2 0.27 m with both front feet held
up (issue 29). Why 80 N m s/rad on the stance legs: the body sinks slowly enough to stay
where it was (1 s of stale state in a high five's hold, on three feet: 1.6 cm of travel,
1.7 cm down; 3.2 cm at 40; at 5 it collapses: 10.2 cm, 19 cm down, 21.5 deg), and 1 on a
leg in the air lets it come down rather than be held. See docs/dds.md, "When the state
stops", for the figures.
"""

from __future__ import annotations

import enum
import math
from concurrent.futures import Future
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from actions.goal_status import GoalStatus
from actions.robot.robot_capabilities import DescribesStream
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real
from wbc.model.description import JOINT_NAMES, Go2Description

if TYPE_CHECKING:
    from actions.action_client import ActionClient
    from actions.action_runner import ActionRunner
    from actions.client_goal_handle import ClientGoalHandle
    from actions.go2.robot_context import RobotContext
    from actions.robot.loop_behaviours import LoopBehaviours
    from actions.robot.robot_interface import MappedRobot
    from wbc.controller.balance_controller import BalanceController
    from wbc.estimation.state_estimator import EstimatorBase

#: Default time [s] over which the held feed-forward ramps to zero.
DEFAULT_DECAY_S = 0.1
#: Default joint damping [N m s/rad] of the fallback on the legs in stance.
DEFAULT_DAMPING_KD = 80.0
#: Default joint damping [N m s/rad] of the fallback on a leg in the air.
DEFAULT_SWING_DAMPING_KD = 1.0


class LoopMode(enum.Enum):
    """Where the loop stands with its state (see the module doc)."""

    WAITING = "waiting"
    CONTROLLING = "controlling"
    FALLBACK = "fallback"
    RECOVERING = "recovering"


# The modes by plain name for the tick's tests: a member looked up on its enum class costs
# about 0.1 us in Python 3.11 (several times that on a loaded machine).
_WAITING, _CONTROLLING, _FALLBACK, _RECOVERING = (
    LoopMode.WAITING, LoopMode.CONTROLLING, LoopMode.FALLBACK, LoopMode.RECOVERING)


@dataclass(frozen=True)
class FallbackSettings:
    """The fallback's numbers.

    Attributes:
        decay_s: Time [s] over which the held feed-forward torques ramp to zero (0: at once).
        damping_kd: Joint damping [N m s/rad] of the fallback command on the legs that were
            in stance when the state was lost.
        swing_damping_kd: Joint damping [N m s/rad] on a leg that was in the air then.
        stand_s: Duration [s] of the ``stand`` goal that recovers the robot.
    """

    decay_s: float = DEFAULT_DECAY_S
    damping_kd: float = DEFAULT_DAMPING_KD
    swing_damping_kd: float = DEFAULT_SWING_DAMPING_KD
    stand_s: float = 2.0

    def __post_init__(self) -> None:
        for name, low in (("decay_s", 0.0), ("damping_kd", 0.0), ("swing_damping_kd", 0.0),
                          ("stand_s", 0.5)):
            value = getattr(self, name)
            if not is_finite_real(value) or value < low:
                raise ConfigurationError(
                    f"{name}: expected a finite number >= {low:g}, received {value!r}")


def decaying_damping(tau_held: np.ndarray, dq: np.ndarray, elapsed_s: float, *,
                     decay_s: float, damping_kd: np.ndarray, tau_max: np.ndarray, message: str,
                     contacts: int = 4) -> ControlOutput:
    """The fallback command ``elapsed_s`` [s] after the state was lost.

    As a motor command: ``tau_ff = max(0, 1 - elapsed_s / decay_s) * tau_held`` [N m],
    ``kp = 0`` (``q_des = 0``, unused), ``dq_des = 0``, ``kd = damping_kd`` [N m s/rad]
    (a number, or one per joint): the drivers
    apply ``tau_ff - damping_kd * dq``. ``tau`` is that torque at the joint velocities
    ``dq`` [rad/s] the loop last had (non-finite ones taken as zero), for a plant that takes
    bare torques, clipped at ``tau_max`` [N m] as the drivers clip; the drivers' own law uses
    their encoders.
    """
    n = len(tau_held)
    # (A tolerance for sums of periods: a hundred 1 ms ticks are 0.1 s, not 0.0999999.)
    share = 0.0 if elapsed_s >= decay_s - 1e-9 else 1.0 - elapsed_s / decay_s
    tau_ff = np.clip(share * np.asarray(tau_held, dtype=float), -tau_max, tau_max)
    velocity = np.asarray(dq, dtype=float)
    velocity = np.where(np.isfinite(velocity), velocity, 0.0)
    kd = np.broadcast_to(np.asarray(damping_kd, dtype=float), (n,)).copy()
    return ControlOutput(
        q_des=np.zeros(n), dq_des=np.zeros(n), kp=np.zeros(n), kd=kd,
        tau_ff=tau_ff, tau=np.clip(tau_ff - kd * velocity, -tau_max, tau_max),
        qdd=np.full(n + 6, np.nan),
        forces=np.full((contacts, 3), np.nan), status=ControlStatus.FALLBACK, message=message,
        timings={"total": 0.0})


@dataclass(frozen=True)
class Transition:
    """A change of :class:`LoopMode` at robot time ``t_s`` [s], and why."""

    t_s: float
    mode: LoopMode
    reason: str

    def as_dict(self) -> dict[str, object]:
        """For a JSON report."""
        return {"t_s": round(self.t_s, 4), "mode": self.mode.name, "reason": self.reason}


class ModeLog:
    """The loop's mode, its reason and every change (for reports and the CLI)."""

    def __init__(self, mode: LoopMode, reason: str, now_s: float) -> None:
        self.mode = mode
        self.reason = reason
        self.since_s = now_s
        self.transitions: list[Transition] = [Transition(now_s, mode, reason)]

    def enter(self, mode: LoopMode, reason: str, now_s: float) -> None:
        """Change to ``mode`` at ``now_s`` [s] (a change of reason alone is not logged)."""
        self.reason = reason
        if mode is self.mode:
            return
        if len(self.transitions) == 1 and now_s <= self.since_s:  # decided at the start
            self.mode = mode
            self.transitions[0] = Transition(now_s, mode, reason)
            return
        self.mode = mode
        self.since_s = now_s
        self.transitions.append(Transition(now_s, mode, reason))

    def summary(self) -> str:
        """The changes after the start, in one line ('' when there were none)."""
        return "; ".join(f"{t.t_s:.2f} s {t.mode.name}" + (f" ({t.reason})" if t.reason else "")
                         for t in self.transitions[1:])


def elapsed_since(log: ModeLog, now_s: float) -> float:
    """Time [s] in the current mode at ``now_s`` (0 for a clock that went back)."""
    return max(0.0, now_s - log.since_s) if math.isfinite(log.since_s) else 0.0


class StandLoop(Protocol):
    """A loop that serves its robot's ``stand`` action."""

    behaviours: LoopBehaviours

    def client(self, action_name: str) -> ActionClient:
        """An action client on the loop's runner."""


def send_stand(loop: StandLoop, duration_s: float) -> Future[ClientGoalHandle]:
    """Send ``loop`` its robot's stand goal of ``duration_s`` [s]
    (:meth:`~actions.robot.loop_behaviours.LoopBehaviours.stand_goal`: the GO2's posture
    transition to standing from wherever the robot is, a foot in the air put down first)."""
    action, goal = loop.behaviours.stand_goal(duration_s)
    return loop.client(action).send_goal_async(goal)


class FallbackLoop(StandLoop, Protocol):
    """What :class:`StateFallback` uses of its loop
    (:class:`~actions.robot.control_loop.ControlLoop`)."""

    robot: MappedRobot
    controller: BalanceController
    context: RobotContext
    runner: ActionRunner
    estimator: EstimatorBase | None


class StateFallback:
    """The loop's modes (module doc): what it commands for the state it has, and the way
    back to control. One per :class:`~actions.robot.control_loop.ControlLoop`
    (``loop.fallback``); both the simulated and the wall-clock loop command through it.

    Args:
        loop: The control loop.
        settings: The decay, the damping and the recovery stand's duration.
    """

    def __init__(self, loop: FallbackLoop, settings: FallbackSettings | None = None) -> None:
        self.loop = loop
        self.settings = settings or FallbackSettings()
        self.log = ModeLog(LoopMode.CONTROLLING, "", loop.robot.time_s)
        self._held = np.zeros(len(JOINT_NAMES))
        self._tau_max = Go2Description.default().effort_limit
        #: The fallback's joint damping [N m s/rad] (12,), description order.
        self.kd = np.full(len(JOINT_NAMES), self.settings.damping_kd)
        self._stand: Future[ClientGoalHandle] | None = None

    @property
    def mode(self) -> LoopMode:
        """The current mode."""
        return self.log.mode

    def wait(self, problem: str, now_s: float) -> None:
        """No sample can start the estimator yet (``problem`` says why): ``WAITING``."""
        reason = f"waiting for a sensor sample to start the state estimator from: {problem}"
        self.log.enter(LoopMode.WAITING, reason, now_s)
        self._held[:] = 0.0
        self.kd[:] = self.settings.damping_kd
        self.loop.context.goal_refusal = reason

    def command(self, q: np.ndarray, v: np.ndarray, *, stale: str = "") -> ControlOutput:
        """This tick's command for the state ``(q, v)``; ``stale`` is a watchdog's reason
        when it found the state stale ('' when not)."""
        loop, log = self.loop, self.log
        now = loop.context.now_s
        untrusted = self.untrusted() or stale
        mode = log.mode
        if untrusted:
            if mode is _CONTROLLING or mode is _RECOVERING:
                self._lose(untrusted, v, now)
            else:
                log.reason = untrusted if mode is _FALLBACK else log.reason
            return decaying_damping(
                self._held, v[6:], elapsed_since(log, now), decay_s=self.settings.decay_s,
                damping_kd=self.kd, tau_max=self._tau_max, message=log.reason)
        if mode is _CONTROLLING:  # the common tick
            return loop.controller.step(q, v)
        if mode is _WAITING or mode is _FALLBACK:
            self._recover(q, v, now)
        if log.mode is _RECOVERING:
            self._follow_stand(now)
        return loop.controller.step(q, v)

    def untrusted(self) -> str:
        """Why the estimate cannot be used this tick ('' when it can)."""
        estimator = self.loop.estimator
        if estimator is None:
            return ""
        if not estimator.started:
            return self.log.reason
        estimate = estimator.estimate
        if estimate.usable:
            return ""
        return (f"state estimate: no trustworthy sensor sample for "
                f"{estimate.untrusted_s * 1e3:.0f} ms (limit "
                f"{estimator.config.trust_timeout_s * 1e3:g} ms): {estimate.faults}"
                + stream_note(self.loop.robot.robot))


    def _lose(self, reason: str, v: np.ndarray, now_s: float) -> None:
        loop = self.loop
        # The controller's own safe command: the torques to decay from; it also releases
        # the controller's references.
        self._held[:] = loop.controller.safe_command(v, reason).tau_ff
        # A leg in the air is let down fast; the legs that carry the body yield slowly.
        stance = set(loop.controller.schedule.stance_legs)
        for j, name in enumerate(JOINT_NAMES):
            self.kd[j] = (self.settings.damping_kd if name.split("_")[0] in stance
                          else self.settings.swing_damping_kd)
        self.log.enter(LoopMode.FALLBACK, reason, now_s)
        self._stand = None
        loop.context.goal_refusal = f"no trustworthy state ({reason}); motors damping"
        loop.context.admit_once = None
        loop.runner.abort_goals(now_s, f"the state stopped being trustworthy ({reason})")

    def _recover(self, q: np.ndarray, v: np.ndarray, now_s: float) -> None:
        loop = self.loop
        estimator = loop.estimator
        how = ("the state estimator started" if self.log.mode is LoopMode.WAITING else
               "trustworthy state back" + (", the state estimator started again"
                                           if estimator is not None and estimator.restarts
                                           else ""))
        if estimator is not None and estimator.start_note:
            how += f" ({estimator.start_note})"
        loop.controller.reset(q, v)
        self.log.enter(LoopMode.RECOVERING, f"{how}: standing the robot up", now_s)
        loop.context.goal_refusal = "standing up after a time without trustworthy state"
        self._send_stand()

    def _send_stand(self) -> None:
        action, goal = self.loop.behaviours.stand_goal(self.settings.stand_s)
        self.loop.context.admit_once = type(goal)  # the one goal admitted while refusing
        self._stand = self.loop.client(action).send_goal_async(goal)

    def _follow_stand(self, now_s: float) -> None:
        future = self._stand
        if future is None or not future.done():
            return
        handle = future.result()
        if handle.accepted and not handle.status.is_terminal:
            return
        if handle.accepted and handle.status is GoalStatus.SUCCEEDED:
            self.log.enter(LoopMode.CONTROLLING, "", now_s)
            self.loop.context.goal_refusal = ""
            self._stand = None
            return
        # Refused (a goal was still ending) or not SUCCEEDED: stand again once idle.
        if not self.loop.runner.active_goals():
            self._send_stand()


def stream_note(robot: object) -> str:
    """'; ' and what ``robot``'s stream brought that was not new (states that keep arriving
    but never change, dropped frames), when it says
    (:class:`~actions.robot.robot_capabilities.DescribesStream`: a ``DdsRobot``); else ''.

    ``robot`` is the robot itself (a loop's ``robot.robot``, behind its ``MappedRobot``).
    """
    note = robot.stale_reason() if isinstance(robot, DescribesStream) else ""
    return f"; {note}" if note else ""
