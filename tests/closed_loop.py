"""A minimal 1 kHz loop shared by the closed-loop tests: MuJoCo plant + controller + lift."""

from __future__ import annotations

import time

import numpy as np

from sim.episode_metrics import EpisodeMetrics, EpisodeSummary
from sim.simulator import Go2Simulator
from wbc import LegLift, LiftPhase, WholeBodyController


def settle(sim: Go2Simulator, controller: WholeBodyController, seconds: float) -> None:
    for _ in range(int(round(seconds / sim.timestep_s))):
        sim.step_command(controller.step(*sim.state()))


def run_lift(leg: str = "FR", height_m: float = 0.40, hold_s: float = 2.0,
             interrupt_at_s: float | None = None, **controller_options):
    """Stand 0.3 s, then lift; returns (summary, sim, controller, lift, phases, interrupt info)."""
    sim = Go2Simulator()
    controller = WholeBodyController(**controller_options)
    controller.reset(sim.state()[0])
    settle(sim, controller, 0.3)
    lift = LegLift(controller, leg=leg, height_m=height_m, hold_s=hold_s)
    metrics = EpisodeMetrics(sim, controller.description.effort_limit)
    lift.start(sim.time_s)
    t_start = sim.time_s
    phases = []
    interrupted_in = None
    lift.shoulder_while_holding = None
    wall = time.perf_counter()
    while lift.phase is not LiftPhase.DONE and sim.time_s < t_start + 30.0:
        if interrupt_at_s is not None and interrupted_in is None and sim.time_s - t_start >= interrupt_at_s:
            interrupted_in = lift.phase
            lift.request_lower(sim.time_s)
        phase = lift.update(sim.time_s)
        if not phases or phases[-1] != phase:
            phases.append(phase)
        q, v = sim.state()
        out = controller.step(q, v)
        sim.step_command(out)
        if phase is LiftPhase.HOLDING and lift.shoulder_while_holding is None:
            lift.shoulder_while_holding = controller.shoulder_position(leg)
        tracking = phase in (LiftPhase.RAISING, LiftPhase.HOLDING, LiftPhase.LOWERING)
        error = None
        if tracking:
            actual = sim.foot_positions()[leg]
            error = float(np.linalg.norm(actual - controller.foot_tasks[leg].target))
        metrics.record(out, stance_legs=controller.support_legs(), foot_error_m=error,
                       holding=phase is LiftPhase.HOLDING)
    summary: EpisodeSummary = metrics.summary(time.perf_counter() - wall)
    return summary, sim, controller, lift, phases, interrupted_in
