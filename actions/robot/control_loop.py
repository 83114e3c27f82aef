"""The robot loop (1 kHz by default): sensors, state estimator, actions, controller, drivers.

The same loop runs a simulated GO2 (:class:`sim.control_loop.ControlLoop` builds one) or a
real one: it speaks to the robot through :class:`actions.robot.robot_interface.RobotInterface`
only.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy
from actions.go2.go2_actions import make_go2_runner
from actions.go2.robot_context import RobotContext
from actions.robot.robot_interface import (
    STATE_SOURCES,
    MappedRobot,
    RobotInterface,
    check_robot,
)
from actions.robot.state_fallback import FallbackSettings, LoopMode, StateFallback
from wbc.controller.balance_controller import BalanceController
from wbc.controller.control_output import ControlOutput
from wbc.core.errors import ConfigurationError
from wbc.core.validation import check_name
from wbc.estimation.estimators import make_estimator
from wbc.estimation.state_estimator import EstimatorBase
from wbc.model.description import JOINT_NAMES, LEGS, Go2Description
from wbc.robot_io.motor_command import within_effort_limits
from wbc.robot_io.sensor_record import SensorRecord

TickHook = Callable[["ControlLoop", ControlOutput], None]


class ControlLoop:
    """Reads the robot, estimates its state, ticks the actions, runs the controller, writes
    the motor command.

    ``spin_once()`` is one control period, in simulated time; it is registered with the
    runner so that ``ActionClient.send_goal_and_wait`` drives the loop when called from
    the same thread (as ``rclpy.spin_until_future_complete`` does).

    The controller sees what a GO2 measures: each tick the robot's sensor record goes
    through a state estimator (by default :class:`wbc.InvariantEkf`: IMU, joint encoders,
    foot contact, and the controller's contact schedule) to the controller's ``(q, v)``.
    When the estimator has had no trustworthy sample for longer than its
    ``trust_timeout_s``, the loop falls back (:mod:`actions.robot.state_fallback`): the
    running goal ends ABORTED with the reason, the held torques decay to pure joint
    damping, goals are refused; when trustworthy samples return, the estimator starts again
    from them and a ``stand`` goal stands the robot up before goals are accepted again. A
    loop whose robot has no usable sample at start waits the same way.
    ``state="truth"`` hands the controller the simulator's exact state instead (a simulator
    only; for comparisons).

    Example:
        >>> loop = ControlLoop(robot, WholeBodyController())   # any RobotInterface
        >>> client = loop.client("high_five")
        >>> result = client.send_goal_and_wait(HighFiveGoal(target_height=0.4, hold_seconds=2))
    """

    def __init__(self, robot: RobotInterface, controller: BalanceController, *,
                 busy_policy: BusyPolicy = BusyPolicy.REJECT,
                 aliases: dict[str, str] | None = None, state: str = "estimate",
                 estimator: EstimatorBase | None = None,
                 fallback: FallbackSettings | None = None):
        """Args:
            robot: The robot in its own joint order (simulated or real).
            controller: The balance controller (reset to the robot's state here).
            busy_policy: What a goal for a busy robot gets.
            aliases: The robot's joint names mapped to the description's, where they differ.
            state: ``estimate`` (the default: the state estimator on the robot's sensors) or
                ``truth`` (the robot's exact state: simulators only).
            estimator: The state estimator (by default :mod:`wbc.estimation.estimators`' default
                for the controller's control period); started on the robot's first sample
                that can start it, on four loaded feet (until then the loop waits, damping).
            fallback: The fallback's decay, damping and recovery stand
                (:class:`~actions.robot.state_fallback.FallbackSettings`).

        Raises:
            UnknownNameError: An unknown ``state``.
            ConfigurationError: A robot that lacks a member or does not declare its
                orders (:func:`~actions.robot.robot_interface.check_robot`: every missing
                one named), ``truth`` from a robot that does not know its exact state or
                with an estimator.
        """
        check_name("state source", state, STATE_SOURCES)
        check_robot(robot, state=state)  # every missing member named, before any is used
        if state == "truth" and estimator is not None:
            raise ConfigurationError(
                "estimator: given with state='truth', which reads no sensors; give "
                "state='estimate' (the default) to run it")
        self.robot = MappedRobot(robot, aliases=aliases)
        self.controller = controller
        self.state_source = state
        self.context = RobotContext(controller)
        self.runner: ActionRunner = make_go2_runner(self.context, busy_policy=busy_policy)
        self.runner.set_spinner(self.spin_once)
        self._bounds = np.zeros(len(LEGS))
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
        if not estimator.started:
            problem = estimator.start_problem(record)
            if problem:
                self.fallback.wait(problem, self.robot.time_s)
                return estimator.estimate.q.copy(), estimator.estimate.v.copy()
            estimate = estimator.reset(record)
        else:
            self.controller.schedule.normal_force_bounds(self._bounds)
            estimate = estimator.update(record, self._bounds)
        return estimate.q.copy(), estimate.v.copy()

    def true_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's exact ``(q, v)``, for metrics and tests (simulated robots only)."""
        return self.robot.read_state()

    def command(self, q: np.ndarray, v: np.ndarray, *, stale: str = "") -> ControlOutput:
        """The controller's tick, or the fallback while the state is not trustworthy
        (:class:`~actions.robot.state_fallback.StateFallback`); ``stale``: a watchdog's
        reason when it found the state stale."""
        return self.fallback.command(q, v, stale=stale)

    @property
    def ready(self) -> bool:
        """The loop controls the robot and accepts goals (``CONTROLLING``)."""
        return self.fallback.mode is LoopMode.CONTROLLING

    def spin_once(self) -> ControlOutput:
        """One control period."""
        q, v = self.read_state()
        self.runner.tick(self.context.now_s)
        out = self.guard(self.command(q, v), v)
        self.context.record_output(out)
        self.last_output = out
        self.robot.write_command(out)
        for hook in self.hooks:
            hook(self, out)
        return out

    def guard(self, out: ControlOutput, v: np.ndarray) -> ControlOutput:
        """``out``, or the controller's safe command when a driver should refuse it.

        Refused: a non-finite value, a negative gain, a feed-forward or resulting torque
        beyond the effort limits (see :meth:`wbc.robot_io.motor_command.MotorCommand.problems`).
        """
        limit = self._effort_limit
        problem = out.problems(limit, JOINT_NAMES)
        if not problem and not within_effort_limits(out.tau, limit):
            problem = "tau: non-finite or beyond the effort limits"
        if not problem:
            return out
        return self.controller.safe_command(v, f"command rejected: {problem}")

    def spin_for(self, seconds: float) -> None:
        """Run for ``seconds`` of robot time."""
        end = self.robot.time_s + seconds - 1e-9
        while self.robot.time_s < end:
            self.spin_once()

    def shutdown(self) -> None:
        """End every goal with a result; the loop can still spin (holding the robot)."""
        self.runner.shutdown(self.robot.time_s)
