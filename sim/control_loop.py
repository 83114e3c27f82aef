"""The control loop on a simulated GO2: :class:`ControlLoop` with :meth:`ControlLoop.simulated`,
which builds the MuJoCo plant, its sensors and the default controller around the robot loop
(:class:`actions.robot.control_loop.ControlLoop`)."""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral
from typing import Protocol, runtime_checkable

from actions.action_runner import BusyPolicy
from actions.robot.control_loop import ControlLoop as Go2Loop
from actions.robot.control_loop import TickHook
from actions.robot.robot_interface import STATE_SOURCES, RobotInterface
from sim.disturbances import DelayedRobot
from sim.mujoco_robot import MujocoRobot, physics_steps_per_period
from sim.plant import DEFAULT_PLANT, Plant
from sim.sensor_faults import FaultyRobot, SensorFault
from sim.sensors import DEFAULT_SENSORS, SensorModel
from sim.simulator import Go2Simulator
from wbc.controller.balance_controller import BalanceController
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.core.validation import check_name, is_finite_real
from wbc.estimation.state_estimator import EstimatorBase

__all__ = ["PHYSICS_TIMESTEP_S", "ControlLoop", "SimulatedLoop", "TickHook"]

#: Default physics timestep [s] of a simulated loop.
PHYSICS_TIMESTEP_S = 1e-3


@runtime_checkable
class SimulatedLoop(Protocol):
    """A loop on a MuJoCo GO2 (one built by :meth:`ControlLoop.simulated`): its simulator is
    :attr:`sim` (a loop built on a robot directly has none)."""

    sim: Go2Simulator


class ControlLoop(Go2Loop):
    """The robot loop on a simulated GO2, whose simulator is :attr:`sim`.

    Example:
        >>> loop = ControlLoop.simulated()
        >>> client = loop.client("high_five")
        >>> result = client.send_goal_and_wait(HighFiveGoal(target_height=0.4, hold_seconds=2))
    """

    #: The MuJoCo GO2 the loop runs on.
    sim: Go2Simulator

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
        # Named here: the plant would otherwise round a period of 1.5 ms to 2 physics steps.
        if not is_finite_real(control_period_s) or not 0 < control_period_s <= 0.1:
            raise ConfigurationError(f"control_period_s: expected a number in (0, 0.1] s, a "
                                     f"whole number of physics steps, received "
                                     f"{control_period_s!r}")
        if (isinstance(sensor_seed, bool) or not isinstance(sensor_seed, Integral)
                or sensor_seed < 0):
            raise ConfigurationError(f"sensor_seed: expected a whole number >= 0 (the seed of "
                                     f"the sensors' noise and biases), received {sensor_seed!r}")
        if physics_timestep_s is None:
            physics_timestep_s = min(PHYSICS_TIMESTEP_S, control_period_s)
        check_name("state source", state, STATE_SOURCES)
        sim = Go2Simulator(actuator_order=actuator_order, plant=plant,
                           timestep_s=physics_timestep_s)
        physics_steps_per_period(control_period_s, sim.timestep_s)  # 1.5 ms on 1 ms: refused
        plant_robot = MujocoRobot(sim, control_period_s=control_period_s, sensors=sensors,
                                  sensor_seed=sensor_seed)
        robot: RobotInterface = plant_robot
        if command_delay_ticks:
            robot = DelayedRobot(robot, command_delay_ticks)
        if sensor_faults:
            robot = FaultyRobot(robot, sensor_faults,
                                foot_full_scale=plant_robot.sensors.model.foot_force_full_scale)
        if controller is None:
            controller = WholeBodyController(solver={"control_period_s": control_period_s})
        period = controller.control_period_s
        if abs(period - control_period_s) > 1e-12:
            raise ConfigurationError(
                f"control_period_s: the controller is configured for {period:g} s, the loop "
                f"for {control_period_s:g} s; give both the same period")
        sim.reset(pose)
        plant_robot.sensors.reset()
        loop = cls(robot, controller, busy_policy=busy_policy, state=state,
                   estimator=estimator)
        loop.sim = sim
        return loop

