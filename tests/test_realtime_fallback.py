"""The wall-clock loop (``run --dds``) started while the robot sends no usable state: it damps
and says why, stands nobody up on the rest sequence's behalf, starts the estimator on the first
usable state, stands the robot up itself, and then accepts goals; its report and exit summary
list the modes."""

from __future__ import annotations

import numpy as np

from actions.go2.go2_interfaces import HighFiveGoal
from actions.goal_status import GoalStatus
from actions.robot.control_loop import ControlLoop
from actions.robot.state_fallback import LoopMode
from sim.cli.run_dds import _summary
from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from tests.test_dds_controller import PERIOD_S, FakeClock, TestRobot, realtime, tick_until
from wbc.controller.control_output import ControlStatus
from wbc.controller.whole_body_controller import WholeBodyController


def test_a_wall_clock_loop_without_state_at_start_waits_then_stands_the_robot_up():
    clock = FakeClock()
    sim = Go2Simulator(timestep_s=1e-3)
    plant = MujocoRobot(sim, control_period_s=PERIOD_S, sensor_seed=0)
    sim.reset("standing")
    plant.sensors.reset()
    robot = TestRobot(plant, clock)
    robot.dropping = True
    loop = ControlLoop(robot, WholeBodyController(solver={"control_period_s": PERIOD_S}))
    assert loop.fallback.mode is LoopMode.WAITING and not loop.ready
    rt = realtime(loop, clock)
    rt.start()
    assert rt.rest.stand is None  # the loop stands the robot once it has a state
    future = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3))
    for _ in range(25):  # 50 ms without a state
        rt.tick()
        out = rt.last_output
        assert out.status is ControlStatus.FALLBACK and (out.kp == 0).all()
        assert (out.tau_ff == 0).all() and (out.kd == 80.0).all()
    assert out.message == ("waiting for a sensor sample to start the state estimator from: no "
                           "sensor sample")
    assert future.result().rejection.message == (
        "robot not able: waiting for a sensor sample to start the state estimator from: no "
        "sensor sample")
    robot.dropping = False
    rt.tick()
    assert loop.fallback.mode is LoopMode.RECOVERING
    assert rt.last_output.status is ControlStatus.OK
    tick_until(rt, lambda: loop.ready, "the stand to succeed", 1100)  # 2 s at 500 Hz
    q, _ = plant.read_state()
    assert q[2] > 0.3
    done = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3))
    rt.tick()
    assert done.result().accepted
    modes = rt.report()["modes"]
    assert [m["mode"] for m in modes] == ["WAITING", "RECOVERING", "CONTROLLING"]
    assert np.isclose(modes[1]["t_s"], 0.05, atol=2.5e-3)
    summary = _summary(rt.report())
    assert ("\n  loop modes:\n  0.05 s: RECOVERING (the state estimator started: standing the "
            "robot up)\n  2.05 s: CONTROLLING") in summary
    assert done.result().status in (GoalStatus.ACCEPTED, GoalStatus.EXECUTING)
