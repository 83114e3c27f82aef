"""The control loop (1 kHz by default) that wires a plant, the whole-body controller and the action runner."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy
from actions.go2_actions import make_go2_runner
from actions.robot_context import RobotContext
from actions.robot_interface import MappedRobot, RobotInterface
from sim.mujoco_robot import MujocoRobot
from sim.plant import DEFAULT_PLANT, Plant
from sim.simulator import Go2Simulator
from wbc.balance_controller import BalanceController
from wbc.control_output import ControlOutput
from wbc.description import JOINT_NAMES, Go2Description
from wbc.errors import ConfigurationError
from wbc.motor_command import within_effort_limits
from wbc.whole_body_controller import WholeBodyController

TickHook = Callable[["ControlLoop", ControlOutput], None]
#: Default physics timestep [s] of a simulated loop.
PHYSICS_TIMESTEP_S = 1e-3


class ControlLoop:
    """Reads the robot, ticks the actions, runs the controller, writes the motor command.

    ``spin_once()`` is one control period, in simulated time; it is registered with the
    runner so that ``ActionClient.send_goal_and_wait`` drives the loop when called from
    the same thread (as ``rclpy.spin_until_future_complete`` does).

    Example:
        >>> loop = ControlLoop.simulated()
        >>> client = loop.client("high_five")
        >>> result = client.send_goal_and_wait(HighFiveGoal(target_height=0.4, hold_seconds=2))
    """

    def __init__(self, robot: RobotInterface, controller: BalanceController, *,
                 busy_policy: BusyPolicy = BusyPolicy.REJECT,
                 aliases: dict[str, str] | None = None):
        """Args:
            robot: The robot in its own joint order (simulated or real).
            controller: The balance controller (reset to the robot's state here).
            busy_policy: What a goal for a busy robot gets.
            aliases: The robot's joint names mapped to the description's, where they differ.
        """
        self.robot = MappedRobot(robot, aliases=aliases)
        self.controller = controller
        self.context = RobotContext(controller)
        self.runner: ActionRunner = make_go2_runner(self.context, busy_policy=busy_policy)
        self.runner.set_spinner(self.spin_once)
        q, v = self.robot.read_state()
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
                  controller: BalanceController | None = None) -> ControlLoop:
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

        Raises:
            ConfigurationError: A control period that is not a whole number of physics steps,
                or a controller configured for another period.
        """
        if physics_timestep_s is None:
            physics_timestep_s = min(PHYSICS_TIMESTEP_S, control_period_s)
        sim = Go2Simulator(actuator_order=actuator_order, plant=plant,
                           timestep_s=physics_timestep_s)
        robot = MujocoRobot(sim, control_period_s=control_period_s)
        if controller is None:
            controller = WholeBodyController(control_period_s=control_period_s)
        period = getattr(getattr(controller, "config", None), "control_period_s", None)
        if period is not None and abs(period - control_period_s) > 1e-12:
            raise ConfigurationError(
                f"control_period_s: the controller is configured for {period:g} s, the loop "
                f"for {control_period_s:g} s; give both the same period")
        sim.reset(pose)
        loop = cls(robot, controller, busy_policy=busy_policy)
        loop.sim = sim
        return loop

    def client(self, action_name: str) -> ActionClient:
        """An action client for ``action_name`` on this loop's runner."""
        return ActionClient(self.runner, action_name)

    def spin_once(self) -> ControlOutput:
        """One control period."""
        now = self.robot.time_s
        q, v = self.robot.read_state()
        self.context.observe(now, q, v)
        self.runner.tick(now)
        out = self.guard(self.controller.step(q, v), v)
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
