"""The GO2's action servers on one runner: high_five, stand, sit, follow_joint_trajectory,
walk; and the velocity stream (``cmd_vel``) that sends walk goals.

Each action is one line of :data:`GO2_SERVED`: its name, its interface (made from its
``.action`` file, :mod:`actions.go2.go2_interfaces`), its behaviour and its goal check. Adding
an action takes its ``.action`` file in ``actions/interfaces/``, its behaviour and one line
here, e.g. ``Go2Action("wave", ACTION_TYPES["Wave"], WaveBehaviour)``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Any

from actions.action_client import ActionClient
from actions.action_runner import ActionRunner
from actions.action_server import ActionServer, Decision
from actions.action_type import ActionType
from actions.behaviour import Behaviour
from actions.busy_policy import BusyPolicy
from actions.go2.follow_joint_trajectory_behaviour import (
    FollowJointTrajectoryBehaviour,
    validate_follow_joint_trajectory_goal,
)
from actions.go2.go2_interfaces import (
    HIGH_FIVE,
    SIT,
    STAND,
    WALK,
    SitFeedback,
    SitResult,
    StandFeedback,
    StandResult,
)
from actions.go2.high_five_behaviour import (
    ROBOT_NOT_READY,
    HighFiveBehaviour,
    validate_high_five_goal,
)
from actions.go2.pose_behaviour import PoseBehaviour, validate_pose_goal
from actions.go2.robot_context import RobotContext
from actions.go2.walk_behaviour import (
    ROBOT_WALKING,
    WalkBehaviour,
    stream_goal,
    validate_walk_goal,
)
from actions.responses import GoalResponse, Rejection
from actions.ros_interfaces.control_msgs import FOLLOW_JOINT_TRAJECTORY

#: Action names served for the GO2.
HIGH_FIVE_ACTION, STAND_ACTION, SIT_ACTION = "high_five", "stand", "sit"
FOLLOW_JOINT_TRAJECTORY_ACTION = "follow_joint_trajectory"
WALK_ACTION = "walk"


@dataclass(frozen=True)
class Go2Action:
    """One action the GO2 serves, as a line of :data:`GO2_SERVED`.

    Attributes:
        name: The name clients use, e.g. ``"high_five"``.
        interface: The action type, e.g. ``HIGH_FIVE``.
        behaviour: Makes the behaviour of an accepted goal from the robot's context (a
            Behaviour class taking the context first, or a ``functools.partial`` of one).
        goal_callback: ``goal_callback(context, goal)`` accepts or rejects a goal (see
            :class:`~actions.action_server.ActionServer`); ``None`` accepts every goal.
        max_unwind_s: Longest unwind [s] after a cancel before the runner aborts the goal.
    """

    name: str
    interface: ActionType
    behaviour: Callable[[RobotContext], Behaviour[Any, Any, Any]]
    goal_callback: Callable[[RobotContext, Any], Decision] | None = None
    max_unwind_s: float = 3.0

    def serve(self, runner: ActionRunner, context: RobotContext) -> ActionServer:
        """The action's server on ``runner``, its behaviours and goal checks on ``context``."""
        goal_callback = partial(_gated, context, self.goal_callback, self.name == WALK_ACTION)
        return ActionServer(runner, self.interface, self.name, partial(self.behaviour, context),
                            goal_callback=goal_callback, max_unwind_s=self.max_unwind_s)


def _gated(context: RobotContext, callback: Callable[[RobotContext, Any], Decision] | None,
           walk: bool, goal: Any) -> Decision:
    """A goal refused while the loop has no trustworthy state (``context.goal_refusal``),
    a goal other than a ``walk`` (``walk`` False) refused while the robot walks, else
    ``callback``'s decision (accepted when there is none)."""
    if context.goal_refusal:
        if context.admit_once is not None and isinstance(goal, context.admit_once):
            context.admit_once = None
        else:
            return Rejection(ROBOT_NOT_READY, f"robot not able: {context.goal_refusal}")
    if context.walking and not walk:
        return Rejection(ROBOT_WALKING, (
            f"robot walking (for {context.walking}): stop it first (cancel the walk goal, or "
            "send a zero velocity command); it stops on four feet within a second"))
    return GoalResponse.ACCEPT if callback is None else callback(context, goal)


#: The GO2's actions, one line each.
GO2_SERVED: tuple[Go2Action, ...] = (
    Go2Action(HIGH_FIVE_ACTION, HIGH_FIVE, HighFiveBehaviour, validate_high_five_goal),
    Go2Action(STAND_ACTION, STAND, partial(
        PoseBehaviour, pose="standing", result_type=StandResult, feedback_type=StandFeedback,
        phase_name="rising"), validate_pose_goal),
    Go2Action(SIT_ACTION, SIT, partial(
        PoseBehaviour, pose="lying", result_type=SitResult, feedback_type=SitFeedback,
        phase_name="sitting"), validate_pose_goal),
    Go2Action(FOLLOW_JOINT_TRAJECTORY_ACTION, FOLLOW_JOINT_TRAJECTORY,
              FollowJointTrajectoryBehaviour, validate_follow_joint_trajectory_goal),
    Go2Action(WALK_ACTION, WALK, WalkBehaviour, validate_walk_goal),
)
#: What :func:`make_go2_runner` serves, action name -> interface, for listing the actions
#: without building a robot (``go2-wbc actions``).
GO2_ACTIONS: dict[str, ActionType] = {
    action.name: action.interface for action in sorted(GO2_SERVED, key=lambda a: a.name)}


def make_go2_runner(context: RobotContext, *,
                    busy_policy: BusyPolicy = BusyPolicy.REJECT) -> ActionRunner:
    """An :class:`ActionRunner` serving the GO2's actions on ``context``'s robot.

    One goal runs at a time; ``busy_policy`` says what a goal for a busy robot gets
    (rejected, or the running goal is preempted: see :class:`BusyPolicy`). The context's
    velocity stream sends its walk goals to the runner's ``walk`` server.
    """
    runner = ActionRunner(busy_policy=busy_policy)
    for action in GO2_SERVED:
        action.serve(runner, context)
    context.velocity_stream.attach(ActionClient(runner, WALK_ACTION).send_goal_async, stream_goal)
    return runner
