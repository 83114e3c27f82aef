"""The robot loop: sensors, state estimator, actions, controller, drivers, one tick written
once in stages (:mod:`actions.robot.robot_tick`).

The same loop runs a simulated GO2 or a real one: it speaks to the robot through
:class:`actions.robot.robot_interface.RobotInterface` only, and to the robot's behaviours
through :class:`~actions.robot.loop_behaviours.LoopBehaviours` (the GO2's are injected by
:class:`~actions.robot.control_loop.ControlLoop`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, cast

import numpy as np

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy
from actions.robot.robot_interface import STATE_SOURCES, MappedRobot, RobotInterface, check_robot
from actions.robot.robot_tick import UNTIMED, Stage, TickFilter, TickTimer
from actions.robot.state_fallback import FallbackSettings, LoopMode, StateFallback
from wbc.controller.balance_controller import BalanceController
from wbc.controller.control_output import ControlOutput
from wbc.core.errors import ConfigurationError
from wbc.core.validation import check_name
from wbc.estimation.estimators import make_estimator
from wbc.estimation.state_estimator import EstimatorBase
from wbc.model.description import JOINT_NAMES, Go2Description
from wbc.robot_io.motor_command import command_and_torque_fine, within_effort_limits
from wbc.robot_io.sensor_record import SensorRecord

if TYPE_CHECKING:
    from actions.robot.loop_behaviours import LoopBehaviours

TickHook = Callable[["RobotLoop", ControlOutput], None]
# The stages by plain name: the tick marks eight of them, and a member looked up on its enum
# class costs about 0.1 us in Python 3.11 (several times that on a loaded machine).
_READ, _ESTIMATE, _ACTIONS, _CONTROLLER, _GUARD, _WRITE, _RELAY, _HOOKS = Stage


class RobotLoop:
    """Reads the robot, estimates its state, ticks the actions, runs the controller, writes
    the motor command: :meth:`tick`, in stages.

    The generic loop: the robot's behaviours (its context, its action runner, its stand and
    sit goals) come from the caller; :class:`~actions.robot.control_loop.ControlLoop` is
    this loop with the GO2's. See that class for the states the loop is in.

    Args:
        robot: The robot in its own joint order (simulated or real).
        controller: The balance controller (reset to the robot's state here).
        behaviours: The robot's behaviours.
        busy_policy: What a goal for a busy robot gets.
        aliases: The robot's joint names mapped to the description's, where they differ.
        state: ``estimate`` (the state estimator on the robot's sensors) or ``truth``
            (the robot's exact state: simulators only).
        estimator: The state estimator (by default :mod:`wbc.estimation.estimators`' default
            for the controller's control period).
        fallback: The fallback's decay, damping and recovery stand.

    Raises:
        UnknownNameError: An unknown ``state``.
        ConfigurationError: A robot that lacks a member or does not declare its orders
            (:func:`~actions.robot.robot_interface.check_robot`: every missing one named),
            ``truth`` from a robot that does not know its exact state or with an estimator.
    """

    def __init__(self, robot: RobotInterface, controller: BalanceController, *,
                 behaviours: LoopBehaviours, busy_policy: BusyPolicy = BusyPolicy.REJECT,
                 aliases: dict[str, str] | None = None, state: str = "estimate",
                 estimator: EstimatorBase | None = None,
                 fallback: FallbackSettings | None = None):
        check_name("state source", state, STATE_SOURCES)
        check_robot(robot, state=state)  # every missing member named, before any is used
        if state == "truth" and estimator is not None:
            raise ConfigurationError(
                "estimator: given with state='truth', which reads no sensors; give "
                "state='estimate' (the default) to run it")
        self.robot = MappedRobot(robot, aliases=aliases)
        self.controller = controller
        self.state_source = state
        #: The robot's behaviours: the stand and sit goals of the fallback and rest sequence.
        self.behaviours = behaviours
        self.runner: ActionRunner
        self.context, self.runner = behaviours.serve(controller, busy_policy=busy_policy)
        self.runner.set_spinner(self.spin_once)
        self.estimator: EstimatorBase | None = None
        #: The loop's mode and its fallback while the state is not trustworthy.
        self.fallback = StateFallback(self, fallback)
        if state == "truth":
            q, v = self.robot.read_state()
        else:
            self.estimator = estimator or make_estimator(
                control_period_s=controller.control_period_s)
            q, v = self.estimate_state(self.robot.read_sensors())
        if self.fallback.mode is LoopMode.CONTROLLING:
            controller.reset(q, v)
        self._effort_limit = Go2Description.default().effort_limit
        self.context.observe(self.robot.time_s, q, v)
        self.hooks: list[TickHook] = []
        self.last_output: ControlOutput | None = None

    def client(self, action_name: str) -> ActionClient:
        """An action client for ``action_name`` on this loop's runner."""
        return ActionClient(self.runner, action_name)

    # -- the tick ---------------------------------------------------------------------------

    def tick(self, timer: TickTimer = UNTIMED, filters: Sequence[TickFilter] = (),
             relays: Sequence[Callable[[], None]] = ()) -> ControlOutput | None:
        """One control period, in stages (:mod:`actions.robot.robot_tick`).

        Args:
            timer: Told the tick's start and each stage's end.
            filters: Told after sensing, in order; a command one returns replaces the
                decision (the tick then writes it, runs no hook and returns ``None``).
            relays: Called after the write, before the hooks.

        Returns:
            The command written, unless a filter's replaced it (``None``).
        """
        robot, mark = self.robot, timer.mark
        timer.start()
        now = robot.time_s
        # -- sense
        if self.estimator is None:
            q, v = robot.read_state()
            fresh = True
            mark(_READ)
        else:
            record = robot.read_sensors()
            fresh = record is not None
            mark(_READ)
            q, v = self.estimate_state(record)
        self.context.observe(now, q, v)
        mark(_ESTIMATE)
        override = None
        for each in filters:
            command = each.sensed(now, fresh)
            if override is None:
                override = command
        # -- decide
        out = None
        if override is None:
            self.runner.tick(now)
            mark(_ACTIONS)
            stale = ""
            for each in filters:
                reason = each.stale(now)
                stale = stale or reason
            decided = self.command(q, v, stale=stale)
            mark(_CONTROLLER)
            out = self.guard(decided, v)
            self.context.record_output(out)
            self.last_output = out
            mark(_GUARD)
            # -- act
            robot.write_command(out)
        else:
            mark(_ACTIONS)
            mark(_CONTROLLER)
            mark(_GUARD)
            robot.write_command(override)
        mark(_WRITE)
        for relay in relays:
            relay()
        mark(_RELAY)
        if out is not None:
            for hook in self.hooks:
                hook(self, out)
        mark(_HOOKS)
        return out

    def spin_once(self) -> ControlOutput:
        """One control period: :meth:`tick`, untimed and without filters (so it decides and
        returns the command it wrote)."""
        return cast(ControlOutput, self.tick())

    def spin_for(self, seconds: float) -> None:
        """Run for ``seconds`` of robot time."""
        end = self.robot.time_s + seconds - 1e-9
        while self.robot.time_s < end:
            self.tick()

    # -- the stages' parts, for a loop driven by hand ---------------------------------------

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The ``(q, v)`` the controller gets this tick (new arrays): the estimate from this
        period's sensor sample and the controller's contact schedule, or the exact state.

        Also what the behaviours see (``context``), so that a loop driven by hand (read,
        ``command``, ``robot.write_command``) keeps them and the loop's hooks up to date.
        """
        now = self.robot.time_s
        if self.estimator is None:
            q, v = self.robot.read_state()
        else:
            q, v = self.estimate_state(self.robot.read_sensors())
        self.context.observe(now, q, v)
        return q, v

    def estimate_state(self, record: SensorRecord | None) -> tuple[np.ndarray, np.ndarray]:
        """The estimator's tick on ``record`` (``None``: no sample this period) and the
        controller's contact schedule; ``(q, v)`` as new arrays.

        Until a sample can start the estimator (finite joints and gyroscope, an attitude:
        :meth:`~wbc.estimation.state_estimator.EstimatorBase.start_problem`) the loop waits
        (:class:`~actions.robot.state_fallback.LoopMode` ``WAITING``); the estimator then
        starts from it, on four loaded feet.
        """
        estimator = self.estimator
        if estimator is None:
            raise ConfigurationError("estimate_state: this loop runs on the exact state "
                                     "(state='truth'), it has no estimator")
        if not estimator.started:
            problem = estimator.start_problem(record)
            if problem or record is None:  # no record: start_problem names why
                self.fallback.wait(problem, self.robot.time_s)
                return estimator.estimate.q.copy(), estimator.estimate.v.copy()
            estimate = estimator.reset(record)
        else:
            bounds = estimator.schedule_input  # filled in place: update copies nothing
            self.controller.schedule.normal_force_bounds(bounds)
            estimate = estimator.update(record, bounds)
        return estimate.q.copy(), estimate.v.copy()

    def true_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's exact ``(q, v)``, for metrics and tests (simulated robots only)."""
        return self.robot.read_state()

    def command(self, q: np.ndarray, v: np.ndarray, *, stale: str = "") -> ControlOutput:
        """The controller's tick, or the fallback while the state is not trustworthy
        (:class:`~actions.robot.state_fallback.StateFallback`); ``stale``: a watchdog's
        reason when it found the state stale."""
        return self.fallback.command(q, v, stale=stale)

    def guard(self, out: ControlOutput, v: np.ndarray) -> ControlOutput:
        """``out``, or the controller's safe command when a driver should refuse it.

        Refused: a non-finite value, a negative gain, a feed-forward or resulting torque
        beyond the effort limits (see :meth:`wbc.robot_io.motor_command.MotorCommand.problems`).
        """
        limit = self._effort_limit
        try:  # float64 vectors, every check passed: one compiled call
            if command_and_torque_fine(out.q_des, out.dq_des, out.kp, out.kd, out.tau_ff,
                                       out.tau, limit):
                return out
        except TypeError:  # not float64 vectors: the checks below say what is wrong
            pass
        problem = out.problems(limit, JOINT_NAMES)
        if not problem and not within_effort_limits(out.tau, limit):
            problem = "tau: non-finite or beyond the effort limits"
        if not problem:
            return out
        return self.controller.safe_command(v, f"command rejected: {problem}")

    @property
    def ready(self) -> bool:
        """The loop controls the robot and accepts goals (``CONTROLLING``)."""
        return self.fallback.mode is LoopMode.CONTROLLING

    def shutdown(self) -> None:
        """End every goal with a result; the loop can still spin (holding the robot)."""
        self.runner.shutdown(self.robot.time_s)
