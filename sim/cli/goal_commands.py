"""``go2-wbc high-five``, ``stand``, ``sit``, ``trajectory``, ``walk``, ``stand-pd``: each builds
its goal."""

from __future__ import annotations

import argparse

import numpy as np

from actions.go2.go2_actions import (
    FOLLOW_JOINT_TRAJECTORY_ACTION,
    HIGH_FIVE_ACTION,
    SIT_ACTION,
    STAND_ACTION,
    WALK_ACTION,
)
from actions.go2.go2_interfaces import HighFiveGoal, SitGoal, StandGoal, WalkGoal
from actions.ros_interfaces.control_msgs import FollowJointTrajectoryGoal
from sim.cli.exit_codes import EXIT_SUCCEEDED
from sim.cli.goal_run import GoalRun
from sim.cli.output import plant_line


def high_five(args: argparse.Namespace) -> int:
    """``go2-wbc high-five``."""
    goal = HighFiveGoal(target_height=args.height, hold_seconds=args.hold)
    return GoalRun(args, HIGH_FIVE_ACTION, goal,
                   f"target_height {goal.target_height:.2f} m, hold {goal.hold_seconds} s").run()


def stand(args: argparse.Namespace) -> int:
    """``go2-wbc stand``: from lying unless ``--start-pose`` says otherwise."""
    args.start_pose = args.start_pose or "lying"
    goal = StandGoal(duration_s=args.duration)
    return GoalRun(args, STAND_ACTION, goal, f"duration {goal.duration_s:g} s").run()


def sit(args: argparse.Namespace) -> int:
    """``go2-wbc sit``."""
    goal = SitGoal(duration_s=args.duration)
    return GoalRun(args, SIT_ACTION, goal, f"duration {goal.duration_s:g} s").run()


def trajectory(args: argparse.Namespace) -> int:
    """``go2-wbc trajectory FILE``."""
    goal: FollowJointTrajectoryGoal = args.file
    points = goal.trajectory.points
    end_s = points[-1].time_from_start.to_seconds() if points else 0.0
    what = (f"{len(goal.trajectory.joint_names)} joint(s), {len(points)} point(s), "
            f"{end_s:g} s")
    return GoalRun(args, FOLLOW_JOINT_TRAJECTORY_ACTION, goal, what).run()


#: How long [s] ``go2-wbc walk`` walks when given neither a duration nor a distance.
WALK_DEFAULT_S = 5.0


def walk(args: argparse.Namespace) -> int:
    """``go2-wbc walk``: a Walk goal, for ``--duration`` or ``--distance``."""
    distance = args.distance or 0.0
    duration = args.duration if args.duration is not None else (
        0.0 if distance else WALK_DEFAULT_S)
    goal = WalkGoal(forward_mps=args.forward, lateral_mps=args.lateral,
                    yaw_rate_radps=args.yaw_rate, duration_s=duration, distance_m=distance)
    span = f"for {distance:g} m" if distance else f"for {duration:g} s"
    return GoalRun(args, WALK_ACTION, goal,
                   f"forward {goal.forward_mps:g} m/s, lateral {goal.lateral_mps:g} m/s, "
                   f"yaw rate {goal.yaw_rate_radps:g} rad/s, {span}").run()


def stand_pd(args: argparse.Namespace) -> int:
    """``go2-wbc stand-pd``: the baseline, a joint PD with gravity compensation (no QP)."""
    from sim.simulator import Go2Simulator
    from wbc.controller.joint_pd_controller import JointPdController

    episode = args.episode
    print(plant_line(episode))
    sim = Go2Simulator(plant=episode.plant_model, timestep_s=episode.timestep_s)
    controller = JointPdController(sim.description.pose("standing"))
    z0 = sim.state()[0][2]
    steps = round(episode.control_period_s / episode.timestep_s)
    # One torque per control period, held over its physics steps (as a driver would).
    for _ in range(max(1, round(args.duration / episode.control_period_s))):
        sim.step(controller.compute(*sim.state()), steps)
    q, _ = sim.state()
    forces = sim.foot_contact_forces()
    print(f"stood {sim.time_s:.2f} s under a joint PD with gravity compensation")
    print(f"base height {z0:.4f} m -> {q[2]:.4f} m; drift {np.linalg.norm(q[:2]) * 1e3:.2f} mm")
    print("foot normal forces [N]: " + ", ".join(f"{k} {v[2]:.1f}" for k, v in forces.items()))
    return EXIT_SUCCEEDED
