"""The controller protocol: its few members, both controllers, and behaviours that use no more."""

from __future__ import annotations

from typing import Any

from actions import (
    FollowJointTrajectoryGoal,
    GoalStatus,
    HighFiveGoal,
    JointTrajectory,
    JointTrajectoryPoint,
    SitGoal,
    StandGoal,
)
from sim.control_loop import ControlLoop
from wbc import WholeBodyController
from wbc.controller.balance_controller import BalanceController

#: Everything the motions, the behaviours and the robot loop may use of a controller.
MEMBERS = {
    "schedule", "description", "control_period_s", "reset", "step", "safe_command",
    "com_target", "set_com_target", "posture_target", "set_posture_target",
    "set_posture_weights", "set_foot_target", "set_foot_weight", "com_position",
    "com_velocity", "foot_positions", "shoulder_position", "normal_force",
}


def protocol_members() -> set[str]:
    return {name for name in vars(BalanceController) if not name.startswith("_")}


class ProtocolOnly:
    """A controller seen through the protocol alone: any other attribute is an error."""

    def __init__(self, controller: Any):
        self._controller = controller
        self.used: set[str] = set()

    def __getattr__(self, name: str) -> Any:
        if name not in MEMBERS:
            raise AttributeError(f"{name}: not a member of the BalanceController protocol")
        self.used.add(name)
        return getattr(self._controller, name)


def test_the_protocol_has_the_few_members_its_users_need(description):
    assert protocol_members() == MEMBERS
    controller = WholeBodyController()
    controller.reset(description.pose("standing"))   # its targets exist from then on
    assert isinstance(controller, BalanceController)


def test_the_behaviours_and_the_loop_run_on_the_protocol_alone():
    controller = ProtocolOnly(WholeBodyController())
    loop = ControlLoop.simulated(controller=controller)
    loop.spin_for(0.2)
    trajectory = JointTrajectory(
        joint_names=["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"],
        points=[JointTrajectoryPoint(positions=[-0.1, 0.2, -1.6], time_from_start=1.0)])
    goals = (("high_five", HighFiveGoal(target_height=0.3, hold_seconds=0)),
             ("follow_joint_trajectory", FollowJointTrajectoryGoal(trajectory=trajectory)),
             ("stand", StandGoal()), ("sit", SitGoal()), ("stand", StandGoal()))
    for name, goal in goals:
        result = loop.client(name).send_goal_and_wait(goal)
        assert result.status is GoalStatus.SUCCEEDED, (name, result.result)
    assert {"schedule", "step", "reset", "foot_positions", "set_foot_weight",
            "control_period_s", "normal_force", "description"} <= controller.used
