"""The GO2's action servers on one runner: high_five, stand, sit, follow_joint_trajectory."""

from __future__ import annotations

from functools import partial

from actions.action_runner import ActionRunner, BusyPolicy
from actions.action_server import ActionServer
from actions.action_type import FOLLOW_JOINT_TRAJECTORY, HIGH_FIVE, SIT, STAND, ActionType
from actions.go2.follow_joint_trajectory_behaviour import (
    FollowJointTrajectoryBehaviour,
    validate_follow_joint_trajectory_goal,
)
from actions.go2.high_five_behaviour import HighFiveBehaviour, validate_high_five_goal
from actions.go2.pose_behaviour import PoseBehaviour, validate_pose_goal
from actions.go2.robot_context import RobotContext
from actions.messages import SitFeedback, SitResult, StandFeedback, StandResult

#: Action names served for the GO2.
HIGH_FIVE_ACTION, STAND_ACTION, SIT_ACTION = "high_five", "stand", "sit"
FOLLOW_JOINT_TRAJECTORY_ACTION = "follow_joint_trajectory"
#: What :func:`make_go2_runner` serves, action name -> interface, for listing the actions
#: without building a robot (``go2-wbc actions``).
GO2_ACTIONS: dict[str, ActionType] = {
    FOLLOW_JOINT_TRAJECTORY_ACTION: FOLLOW_JOINT_TRAJECTORY,
    HIGH_FIVE_ACTION: HIGH_FIVE,
    SIT_ACTION: SIT,
    STAND_ACTION: STAND,
}


def make_go2_runner(context: RobotContext, *,
                    busy_policy: BusyPolicy = BusyPolicy.REJECT) -> ActionRunner:
    """An :class:`ActionRunner` serving the GO2's actions on ``context``'s robot.

    One goal runs at a time; ``busy_policy`` says what a goal for a busy robot gets
    (rejected, or the running goal is preempted: see :class:`BusyPolicy`).
    """
    runner = ActionRunner(busy_policy=busy_policy)
    ActionServer(runner, HIGH_FIVE, HIGH_FIVE_ACTION, partial(HighFiveBehaviour, context),
                 goal_callback=partial(validate_high_five_goal, context), max_unwind_s=3.0)
    ActionServer(runner, STAND, STAND_ACTION,
                 partial(PoseBehaviour, context, "standing", StandResult, StandFeedback,
                         "rising"), goal_callback=validate_pose_goal, max_unwind_s=3.0)
    ActionServer(runner, SIT, SIT_ACTION,
                 partial(PoseBehaviour, context, "lying", SitResult, SitFeedback, "sitting"),
                 goal_callback=validate_pose_goal, max_unwind_s=3.0)
    ActionServer(runner, FOLLOW_JOINT_TRAJECTORY, FOLLOW_JOINT_TRAJECTORY_ACTION,
                 partial(FollowJointTrajectoryBehaviour, context),
                 goal_callback=partial(validate_follow_joint_trajectory_goal, context),
                 max_unwind_s=3.0)
    return runner
