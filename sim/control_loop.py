"""The control loop (1 kHz by default): sensors, state estimator, actions, controller, drivers."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy
from actions.go2_actions import make_go2_runner
from actions.robot_context import RobotContext
from actions.robot_interface import STATE_SOURCES, MappedRobot, RobotInterface
from sim.disturbances import DelayedRobot
from sim.mujoco_robot import MujocoRobot
from sim.plant import DEFAULT_PLANT, Plant
from sim.sensor_faults import FaultyRobot, SensorFault
from sim.sensors import DEFAULT_SENSORS, SensorModel
from sim.simulator import Go2Simulator
from wbc.balance_controller import BalanceController
from wbc.control_output import ControlOutput
from wbc.description import JOINT_NAMES, LEGS, Go2Description
from wbc.errors import ConfigurationError
from wbc.estimators import make_estimator
from wbc.motor_command import within_effort_limits
from wbc.sensor_record import SensorRecord
from wbc.state_estimator import EstimatorBase
from wbc.validation import check_name
from wbc.whole_body_controller import WholeBodyController

TickHook = Callable[["ControlLoop", ControlOutput], None]
#: Default physics timestep [s] of a simulated loop.
PHYSICS_TIMESTEP_S = 1e-3


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
    ``trust_timeout_s``, the loop sends the controller's safe command with the reason
    instead (a running goal then ends ABORTED), and resumes when samples return.
    ``state="truth"`` hands the controller the simulator's exact state instead (a simulator
    only; for comparisons).

    Example:
        >>> loop = ControlLoop.simulated()
        >>> client = loop.client("high_five")
        >>> result = client.send_goal_and_wait(HighFiveGoal(target_height=0.4, hold_seconds=2))
    """

    def __init__(self, robot: RobotInterface, controller: BalanceController, *,
                 busy_policy: BusyPolicy = BusyPolicy.REJECT,
                 aliases: dict[str, str] | None = None, state: str = "estimate",
                 estimator: EstimatorBase | None = None):
        """Args:
            robot: The robot in its own joint order (simulated or real).
            controller: The balance controller (reset to the robot's state here).
            busy_policy: What a goal for a busy robot gets.
            aliases: The robot's joint names mapped to the description's, where they differ.
            state: ``estimate`` (the default: the state estimator on the robot's sensors) or
                ``truth`` (the robot's exact state: simulators only).
            estimator: The state estimator (by default :mod:`wbc.estimators`' default for the
                controller's control period); started here on the robot's first sample, on
                four loaded feet.

        Raises:
            UnknownNameError: An unknown ``state``.
            ConfigurationError: ``truth`` from a robot that does not know its exact state or
                with an estimator, or a first sample the estimator cannot start from (the
                field named).
        """
        check_name("state source", state, STATE_SOURCES)
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
        if state == "truth":
            q, v = self.robot.read_state()
        else:
            period = getattr(getattr(controller, "config", None), "control_period_s", 1e-3)
            self.estimator = estimator or make_estimator(control_period_s=period)
            record = self.robot.read_sensors()
            if record is None:
                raise ConfigurationError(
                    "robot: no sensor sample to start the state estimator from")
            estimate = self.estimator.reset(record)
            q, v = estimate.q.copy(), estimate.v.copy()
        controller.reset(q, v)
        self._effort_limit = Go2Description.default().effort_limit
        self.context.observe(self.robot.time_s, q, v)
        self.hooks: list[TickHook] = []
        self.last_output: ControlOutput | None = None

    @classmethod
    def simulated(cls, *, pose: str = "standing", actuator_order: Sequence[str] | None = None,
                  plant: Plant | str = DEFAULT_PLANT, control_period_s: float = 1e-3,
                  physics_timestep_s: float | None = None,
                  busy_policy: BusyPolicy = BusyPolicy.REJECT,
                  controller: BalanceController | None = None,
                  sensors: SensorModel | str = DEFAULT_SENSORS, sensor_seed: int = 0,
                  state: str = "estimate", estimator: EstimatorBase | None = None,
                  command_delay_ticks: int = 0, sensor_faults: Sequence[SensorFault] = ()
                  ) -> ControlLoop:
        """A loop on a fresh MuJoCo GO2 in ``pose``, with the default whole-body controller.

        Args:
            pose: The pose the robot starts in.
            actuator_order: The plant's actuator order (description order by default).
            plant: The plant's physics: a :class:`sim.plant.Plant` or a preset name
                (default ``menagerie``: joint damping, friction and armature the controller
                does not know).
            control_period_s: Control period [s] (1 ms: 1 kHz; 2 ms: the GO2's usual 500 Hz).
            physics_timestep_s: Physics timestep [s]; a whole number of them makes a control
                period. Default: :data:`PHYSICS_TIMESTEP_S` or the control period if shorter.
            busy_policy: What a goal for a busy robot gets.
            controller: The controller; by default a :class:`WholeBodyController` with this
                control period. A given one must have the same ``control_period_s``.
            sensors: What the robot measures: a :class:`sim.sensors.SensorModel` or a preset
                (default ``go2``: a GO2's noise and biases; ``exact``: no noise).
            sensor_seed: Seed of the sensors' noise and biases.
            state: ``estimate`` (default) or ``truth`` (see the class docstring).
            estimator: The state estimator (a default one when ``None``).
            command_delay_ticks: Control periods between a command and the drivers applying
                it (:class:`sim.disturbances.DelayedRobot`).
            sensor_faults: Sensor faults on the robot's clock
                (:class:`sim.sensor_faults.FaultyRobot`).

        Raises:
            ConfigurationError: A control period that is not a whole number of physics steps,
                or a controller configured for another period.
            UnknownNameError: An unknown sensor preset or state source.
        """
        if physics_timestep_s is None:
            physics_timestep_s = min(PHYSICS_TIMESTEP_S, control_period_s)
        check_name("state source", state, STATE_SOURCES)
        sim = Go2Simulator(actuator_order=actuator_order, plant=plant,
                           timestep_s=physics_timestep_s)
        plant_robot = MujocoRobot(sim, control_period_s=control_period_s, sensors=sensors,
                                  sensor_seed=sensor_seed)
        robot: RobotInterface = plant_robot
        if command_delay_ticks:
            robot = DelayedRobot(robot, command_delay_ticks)
        if sensor_faults:
            robot = FaultyRobot(robot, sensor_faults,
                                foot_full_scale=plant_robot.sensors.model.foot_force_full_scale)
        if controller is None:
            controller = WholeBodyController(control_period_s=control_period_s)
        period = getattr(getattr(controller, "config", None), "control_period_s", None)
        if period is not None and abs(period - control_period_s) > 1e-12:
            raise ConfigurationError(
                f"control_period_s: the controller is configured for {period:g} s, the loop "
                f"for {control_period_s:g} s; give both the same period")
        sim.reset(pose)
        plant_robot.sensors.reset()
        loop = cls(robot, controller, busy_policy=busy_policy, state=state,
                   estimator=estimator)
        loop.sim = sim
        return loop

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
        controller's contact schedule; ``(q, v)`` as new arrays."""
        self.controller.normal_force_bounds(self._bounds)
        estimate = self.estimator.update(record, self._bounds)
        return estimate.q.copy(), estimate.v.copy()

    def true_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The robot's exact ``(q, v)``, for metrics and tests (simulated robots only)."""
        return self.robot.read_state()

    def command(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """The controller's tick, or its safe command while the state is not trustworthy."""
        estimator = self.estimator
        if estimator is not None and not estimator.estimate.usable:
            estimate = estimator.estimate
            return self.controller.safe_command(v, (
                f"state estimate: no trustworthy sensor sample for "
                f"{estimate.untrusted_s * 1e3:.0f} ms (limit "
                f"{estimator.config.trust_timeout_s * 1e3:g} ms): {estimate.faults}"))
        return self.controller.step(q, v)

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
        beyond the effort limits (see :meth:`wbc.motor_command.MotorCommand.problems`).
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
