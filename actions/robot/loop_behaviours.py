"""What the generic robot loop takes from a robot's own behaviours (:class:`LoopBehaviours`):
the context and the action runner it ticks, the goals that stand the robot up and sit it down.

The robot loop (:class:`~actions.robot.robot_loop.RobotLoop`), its fallback
(:mod:`actions.robot.state_fallback`) and its rest sequence
(:mod:`actions.robot.rest_sequence`) know no robot's actions; the GO2's are
:data:`actions.go2.go2_loop_behaviours.GO2_BEHAVIOURS`, which
:class:`~actions.robot.control_loop.ControlLoop` passes.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from actions.action_runner import ActionRunner, BusyPolicy
    from actions.go2.robot_context import RobotContext
    from wbc.controller.balance_controller import BalanceController


class LoopBehaviours(Protocol):
    """A robot's behaviours as the robot loop uses them."""

    @property
    def standing_height_m(self) -> float:
        """Base height [m] below which the robot is down (the rest sequence stands it)."""

    def serve(self, controller: BalanceController, *,
              busy_policy: BusyPolicy) -> tuple[RobotContext, ActionRunner]:
        """The behaviours' view of the robot on ``controller`` and a runner serving the
        robot's actions on it; ``busy_policy``: what a goal for a busy robot gets."""

    def stand_goal(self, duration_s: float) -> tuple[str, Any]:
        """The action and goal that stand the robot up from wherever it is, in
        ``duration_s`` [s]."""

    def sit_goal(self, duration_s: float) -> tuple[str, Any]:
        """The action and goal that lower the robot to rest, in ``duration_s`` [s]."""
