"""The loop the closed-loop lift tests share: a MuJoCo GO2, its sensors and the default state
estimator, a controller and a LegLift driven by hand, measured on the simulator's truth."""

from __future__ import annotations

import time

from sim.control_loop import ControlLoop
from sim.run_recorder import MetricsHook
from wbc import LegLift, LiftPhase, WholeBodyController
from wbc.controller.control_output import ControlOutput


def tick(loop: ControlLoop) -> ControlOutput:
    """One control period by hand: the estimated state, the controller, the command."""
    q, v = loop.read_state()
    out = loop.command(q, v)
    loop.robot.write_command(out)
    return out


def settle(loop: ControlLoop, seconds: float) -> None:
    for _ in range(round(seconds / loop.controller.control_period_s)):
        tick(loop)


def run_lift(leg: str = "FR", height_m: float = 0.40, hold_s: float = 2.0,
             interrupt_at_s: float | None = None, **controller_options):
    """Stand 0.3 s, then lift; returns (summary, loop, controller, lift, phases, interrupt
    info). The raised foot's error is its true position against its target carried into
    the simulator's frame (aligned at the lift's start)."""
    controller = WholeBodyController(**controller_options)
    loop = ControlLoop.simulated(controller=controller)
    settle(loop, 0.3)
    lift = LegLift(controller, leg=leg, height_m=height_m, hold_s=hold_s)
    phase_name = [""]
    hook = MetricsHook(loop, lambda: phase_name[0], leg)
    lift.start(loop.sim.time_s)
    t_start = loop.sim.time_s
    phases = []
    interrupted_in = None
    lift.shoulder_while_holding = None
    wall = time.perf_counter()
    while lift.phase is not LiftPhase.DONE and loop.sim.time_s < t_start + 30.0:
        now = loop.sim.time_s
        if (interrupt_at_s is not None and interrupted_in is None
                and now - t_start >= interrupt_at_s):
            interrupted_in = lift.phase
            lift.request_lower(now)
        q, v = loop.read_state()
        phase = lift.advance(now)
        if not phases or phases[-1] != phase:
            phases.append(phase)
        out = loop.command(q, v)
        loop.robot.write_command(out)
        if phase is LiftPhase.HOLDING and lift.shoulder_while_holding is None:
            lift.shoulder_while_holding = controller.shoulder_position(leg)
        phase_name[0] = {LiftPhase.RAISING: "raising", LiftPhase.HOLDING: "ready",
                         LiftPhase.LOWERING: "lowering"}.get(phase, "")
        hook(loop, out)
    summary = hook.metrics.summary(time.perf_counter() - wall)
    return summary, loop, controller, lift, phases, interrupted_in
