"""The .action files say what the servers do: each phase listed is reported, and no other."""

from __future__ import annotations

import re

import pytest

from actions import (
    ACTION_TYPES,
    FOLLOW_JOINT_TRAJECTORY,
    Duration,
    FollowJointTrajectoryGoal,
    HighFiveGoal,
    JointTrajectory,
    JointTrajectoryPoint,
    SitGoal,
    StandGoal,
    WalkGoal,
)
from actions.action_definition import parse_action_file
from actions.go2.go2_actions import FOLLOW_JOINT_TRAJECTORY_ACTION, GO2_ACTIONS
from sim.control_loop import ControlLoop

#: Faulty ticks: torque limits of 0.1 % of the URDF's, so no tick is OK (a controller fault).
FAULT_TICKS = 10


def listed_phases(action_name: str) -> list[str]:
    """The quoted words of the comment of the feedback's ``string phase`` field, in order."""
    lines = GO2_ACTIONS[action_name].interface_path.read_text().split("\n---\n")[2].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("string phase "))
    comment = [lines[start].split("#", 1)[1]]
    for line in lines[start + 1:]:
        if not line.lstrip().startswith("#"):
            break
        comment.append(line)
    return re.findall(r'"(\w+)"', " ".join(comment))


class Goals:
    """Sends goals to one simulated GO2 and keeps the phases their feedback reports."""

    def __init__(self, pose: str = "standing"):
        self.loop = ControlLoop.simulated(pose=pose)
        self.loop.spin_for(0.3)
        self.phases: dict[str, list[str]] = {name: [] for name in GO2_ACTIONS}

    def run(self, action_name: str, goal, *, cancel_after_s: float | None = None,
            fault_after_s: float | None = None) -> str:
        """Run ``goal`` to its end (canceled or made to fault after that many seconds); returns
        the final status' name."""
        loop, phases = self.loop, self.phases[action_name]

        def on_feedback(message) -> None:
            phase = getattr(message.feedback, "phase", None)
            if phase is not None and (not phases or phases[-1] != phase):
                phases.append(phase)

        handle = loop.client(action_name).send_goal_async(goal, feedback_callback=on_feedback)
        while not handle.done():
            loop.spin_once()
        result = handle.result().get_result_async()
        started_s = loop.robot.time_s
        if cancel_after_s is not None:
            loop.spin_for(cancel_after_s)
            handle.result().cancel_goal_async()
        if fault_after_s is not None:
            loop.spin_for(fault_after_s)
            saved = loop.controller.tau_max
            loop.controller.tau_max = 1e-3 * saved
            loop.spin_for(FAULT_TICKS * 1e-3)
            loop.controller.tau_max = saved
        while not result.done() and loop.robot.time_s < started_s + 30.0:
            loop.spin_once()
        if fault_after_s is not None:
            loop.spin_for(0.1)  # the solver recovers before the next goal
        return result.result().status.name

    def lift_a_foot(self) -> None:
        """A trajectory goal for the FR leg: it ends with the FR foot up."""
        point = JointTrajectoryPoint(positions=[-0.1, -0.3, -1.6],
                                     time_from_start=Duration(sec=1))
        goal = FollowJointTrajectoryGoal(trajectory=JointTrajectory(
            joint_names=["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"], points=[point]))
        assert self.run(FOLLOW_JOINT_TRAJECTORY_ACTION, goal) == "SUCCEEDED"
        assert self.loop.controller.stance_legs == ["FL", "RL", "RR"]


@pytest.fixture(scope="module")
def reported() -> dict[str, set[str]]:
    """Every phase each action reported, over goals that reach each of its phases once: from
    lying and from standing, with a foot in the air, canceled and aborted by a fault."""
    lying = Goals("lying")
    assert lying.run("high_five", HighFiveGoal(target_height=0.3, hold_seconds=0)) == (
        "SUCCEEDED")

    standing = Goals()
    assert standing.run("high_five", HighFiveGoal(target_height=0.3, hold_seconds=0),
                        cancel_after_s=0.5) == "CANCELED"
    assert standing.run("high_five", HighFiveGoal(target_height=0.3, hold_seconds=0),
                        fault_after_s=0.5) == "ABORTED"
    standing.lift_a_foot()
    assert standing.run("sit", SitGoal(duration_s=1.0)) == "SUCCEEDED"
    assert standing.run("stand", StandGoal(duration_s=1.0)) == "SUCCEEDED"
    standing.lift_a_foot()
    assert standing.run("stand", StandGoal(duration_s=1.0)) == "SUCCEEDED"
    for name, goal in (("stand", StandGoal(duration_s=2.0)), ("sit", SitGoal(duration_s=2.0))):
        assert standing.run(name, goal, cancel_after_s=0.5) == "CANCELED"
        assert standing.run("stand", StandGoal(duration_s=1.0)) == "SUCCEEDED"
        assert standing.run(name, goal, fault_after_s=0.5) == "ABORTED"
        assert standing.run("stand", StandGoal(duration_s=1.0)) == "SUCCEEDED"
    return {name: set(lying.phases[name]) | set(standing.phases[name])
            for name in GO2_ACTIONS}


@pytest.mark.parametrize("action_name", ["high_five", "stand", "sit"])
def test_every_phase_reported_is_listed_and_every_listed_one_is_reported(action_name, reported):
    listed = listed_phases(action_name)
    assert len(listed) == len(set(listed))
    assert reported[action_name] == set(listed)


@pytest.mark.slow
def test_walk_reports_every_listed_phase_and_no_other():
    """From lying (``standing`` first), a walk to its end, canceled, aborted by a fault."""
    lying = Goals("lying")
    assert lying.run("walk", WalkGoal(forward_mps=0.3, duration_s=1.0)) == "SUCCEEDED"
    assert lying.run("walk", WalkGoal(forward_mps=0.3, duration_s=3.0),
                     cancel_after_s=1.0) == "CANCELED"
    assert lying.run("walk", WalkGoal(forward_mps=0.3, duration_s=3.0),
                     fault_after_s=1.0) == "ABORTED"
    listed = listed_phases("walk")
    assert len(listed) == len(set(listed))
    assert set(lying.phases["walk"]) == set(listed)


def test_the_listed_phases_in_order():
    assert listed_phases("high_five") == [
        "standing", "shifting", "unloading", "raising", "ready", "lowering", "reloading",
        "shifting_back", "complete", "canceled", "aborted"]
    assert listed_phases("stand") == ["placing_foot", "rising", "complete", "canceled",
                                      "aborted"]
    assert listed_phases("sit") == ["placing_foot", "sitting", "complete", "canceled",
                                    "aborted"]
    assert listed_phases("walk") == ["standing", "starting", "walking", "stopping", "complete",
                                     "canceled", "aborted"]


def test_follow_joint_trajectory_feedback_is_control_msgs_with_no_phase():
    _, _, feedback = parse_action_file(FOLLOW_JOINT_TRAJECTORY.interface_path)
    assert [field.name for field in feedback.fields] == [
        "header", "joint_names", "desired", "actual", "error"]
    assert ACTION_TYPES["FollowJointTrajectory"].type_name == (
        "control_msgs/action/FollowJointTrajectory")
