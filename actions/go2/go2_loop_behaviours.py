"""The GO2's behaviours as the robot loop takes them (:data:`GO2_BEHAVIOURS`): its actions'
runner, the ``stand`` and ``sit`` goals of the fallback and the rest sequence."""

from __future__ import annotations

from actions.action_runner import ActionRunner, BusyPolicy
from actions.go2.go2_actions import SIT_ACTION, STAND_ACTION, make_go2_runner
from actions.go2.go2_interfaces import SitGoal, StandGoal
from actions.go2.robot_context import STANDING_HEIGHT_M, RobotContext
from wbc.controller.balance_controller import BalanceController


class Go2Behaviours:
    """The GO2's :class:`~actions.robot.loop_behaviours.LoopBehaviours`."""

    #: Below it [m] the GO2 is down: the rest sequence stands it up first.
    standing_height_m = STANDING_HEIGHT_M

    def serve(self, controller: BalanceController, *,
              busy_policy: BusyPolicy = BusyPolicy.REJECT
              ) -> tuple[RobotContext, ActionRunner]:
        """A :class:`RobotContext` on ``controller`` and the GO2's actions served on it
        (:func:`~actions.go2.go2_actions.make_go2_runner`)."""
        context = RobotContext(controller)
        return context, make_go2_runner(context, busy_policy=busy_policy)

    def stand_goal(self, duration_s: float) -> tuple[str, StandGoal]:
        """``stand``: the posture transition to standing (a raised foot is put down first)."""
        return STAND_ACTION, StandGoal(duration_s=duration_s)

    def sit_goal(self, duration_s: float) -> tuple[str, SitGoal]:
        """``sit``: the body lowered to the lying pose."""
        return SIT_ACTION, SitGoal(duration_s=duration_s)


#: The GO2's behaviours (what :class:`~actions.robot.control_loop.ControlLoop` passes).
GO2_BEHAVIOURS = Go2Behaviours()
