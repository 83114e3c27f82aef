"""The 1 kHz loop that wires a plant, the whole-body controller and the action runner."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner, BusyPolicy
from actions.go2_actions import make_go2_runner
from actions.robot_context import RobotContext
from actions.robot_interface import MappedRobot, RobotInterface
from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from wbc.balance_controller import BalanceController
from wbc.control_output import ControlOutput
from wbc.description import JOINT_NAMES, Go2Description
from wbc.whole_body_controller import WholeBodyController

TickHook = Callable[["ControlLoop", ControlOutput], None]


class ControlLoop:
    """Reads the robot, ticks the actions, runs the controller, writes torques: 1 kHz.

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
        self._effort_limit = Go2Description().effort_limit
        self.context.observe(self.robot.time_s, q, v)
        self.hooks: list[TickHook] = []
        self.last_output: ControlOutput | None = None

    @classmethod
    def simulated(cls, *, pose: str = "standing", actuator_order: Sequence[str] | None = None,
                  floor_friction: float = 1.0, busy_policy: BusyPolicy = BusyPolicy.REJECT,
                  controller: BalanceController | None = None) -> ControlLoop:
        """A loop on a fresh MuJoCo GO2 in ``pose``, with the default whole-body controller."""
        sim = Go2Simulator(actuator_order=actuator_order, floor_friction=floor_friction)
        sim.reset(pose)
        loop = cls(MujocoRobot(sim), controller or WholeBodyController(), busy_policy=busy_policy)
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
        out = self._guard(self.controller.step(q, v), v)
        self.context.record_output(out)
        self.last_output = out
        self.robot.write_torques(out.tau)
        for hook in self.hooks:
            hook(self, out)
        return out

    def _guard(self, out: ControlOutput, v) -> ControlOutput:
        """Never send a non-finite torque or one beyond the effort limits: fall back."""
        tau = out.tau
        limit = self._effort_limit
        if tau.shape == limit.shape and math.isfinite(tau.sum()) and np.all(np.abs(tau) <= limit):
            return out
        bad = np.flatnonzero(~np.isfinite(tau) | (np.abs(tau) > limit)) if tau.shape == limit.shape else []
        return self.controller.safe_command(
            v, f"command rejected: torques non-finite or beyond the effort limits at joints "
               f"{[JOINT_NAMES[i] for i in bad]}")

    def spin_for(self, seconds: float) -> None:
        """Run for ``seconds`` of robot time."""
        end = self.robot.time_s + seconds - 1e-9
        while self.robot.time_s < end:
            self.spin_once()

    def shutdown(self) -> None:
        """End every goal with a result; the loop can still spin (holding the robot)."""
        self.runner.shutdown(self.robot.time_s)
