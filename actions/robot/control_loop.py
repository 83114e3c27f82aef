"""The GO2's robot loop (1 kHz by default): :class:`ControlLoop`, the generic
:class:`~actions.robot.robot_loop.RobotLoop` with the GO2's behaviours.

The same loop runs a simulated GO2 (:class:`sim.control_loop.ControlLoop` builds one) or a
real one: it speaks to the robot through :class:`actions.robot.robot_interface.RobotInterface`
only.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from actions.action_runner import BusyPolicy
from actions.go2.go2_loop_behaviours import GO2_BEHAVIOURS
from actions.robot.robot_interface import RobotInterface
from actions.robot.robot_loop import RobotLoop, TickHook
from actions.robot.state_fallback import FallbackSettings
from wbc.controller.balance_controller import BalanceController
from wbc.estimation.state_estimator import EstimatorBase

if TYPE_CHECKING:
    from actions.robot.loop_behaviours import LoopBehaviours

__all__ = ["ControlLoop", "TickHook"]


class ControlLoop(RobotLoop):
    """Reads the robot, estimates its state, ticks the GO2's actions, runs the controller,
    writes the motor command.

    ``spin_once()`` is one control period (:meth:`~actions.robot.robot_loop.RobotLoop.tick`),
    in simulated time; it is registered with the runner so that
    ``ActionClient.send_goal_and_wait`` drives the loop when called from the same thread (as
    ``rclpy.spin_until_future_complete`` does).

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
                 fallback: FallbackSettings | None = None,
                 behaviours: LoopBehaviours = GO2_BEHAVIOURS):
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
            behaviours: The robot's behaviours (default: the GO2's,
                :data:`~actions.go2.go2_loop_behaviours.GO2_BEHAVIOURS`).

        Raises:
            UnknownNameError: An unknown ``state``.
            ConfigurationError: A robot that lacks a member or does not declare its
                orders (:func:`~actions.robot.robot_interface.check_robot`: every missing
                one named), ``truth`` from a robot that does not know its exact state or
                with an estimator.
        """
        super().__init__(robot, controller, behaviours=behaviours, busy_policy=busy_policy,
                         aliases=aliases, state=state, estimator=estimator, fallback=fallback)

    def command_velocity(self, forward_mps: float, lateral_mps: float, yaw_rate_radps: float,
                         *, timeout_s: float | None = None) -> None:
        """Stream a velocity command (``cmd_vel``, base heading frame); any thread.

        A command that is not zero starts a walk when the robot is idle (a ``walk`` goal; the
        robot stands up first if it is not standing) and steers the walk it started; a zero
        command, or no command for ``timeout_s`` of the loop's own time (simulated time in
        simulation), stops it on four loaded feet. While another goal runs, the walk is
        refused (``velocity_stream.refusal`` says why).

        Args:
            forward_mps, lateral_mps: Velocity [m/s]; yaw_rate_radps: turning rate [rad/s].
            timeout_s: Robot time [s] without a newer command after which the robot stops
                (default ``velocity_stream.timeout_s``, 0.5 s).

        Raises:
            ConfigurationError: A component beyond the walking limits, or a bad timeout (the
                message names the field, the value and the valid range).
        """
        self.context.velocity_stream.command(forward_mps, lateral_mps, yaw_rate_radps,
                                             timeout_s=timeout_s)
