"""The loop the closed-loop walking tests share: a MuJoCo GO2 on the default (realistic) plant,
its sensors and the default state estimator, the whole-body controller and a Walking driven
by hand; every figure is measured on the simulator's truth."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from sim.control_loop import ControlLoop
from sim.disturbances import Push, PushSchedule
from sim.plant import Plant
from tests.closed_loop import settle, tick
from wbc import WholeBodyController
from wbc.locomotion import GaitParameters, VelocityLimits, Walking, WalkPhase

#: A base this low [m] (standing: 0.335) has fallen.
FALLEN_Z_M = 0.18


def yaw_of(q: np.ndarray) -> float:
    """Heading [rad] of a Pinocchio configuration (quaternion x, y, z, w)."""
    x, y, z, w = q[3:7]
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


@dataclass
class WalkRun:
    """What a walk did, sampled every control tick (truth unless named ``estimated``)."""

    times: list[float] = field(default_factory=list)
    base: list[np.ndarray] = field(default_factory=list)        # true base position [m]
    yaw: list[float] = field(default_factory=list)              # true heading [rad]
    estimated: list[np.ndarray] = field(default_factory=list)   # estimated base position
    phases: list[WalkPhase] = field(default_factory=list)
    fell: bool = False
    failures: int = 0
    done_s: float | None = None     # when the walk ended DONE [s, since the walk's start]
    stop_s: float | None = None     # when the stop was asked for
    wall_s: float = 0.0
    walking: Walking | None = None
    loop: ControlLoop | None = None

    def window(self, start_s: float, end_s: float) -> slice:
        t = np.asarray(self.times)
        return slice(int(np.searchsorted(t, start_s)), int(np.searchsorted(t, end_s)))

    def mean_velocity(self, start_s: float, end_s: float) -> np.ndarray:
        """Mean forward, lateral [m/s] (heading frame at ``start_s``) and yaw rate [rad/s]."""
        w = self.window(start_s, end_s)
        base, yaw = np.asarray(self.base)[w], np.unwrap(np.asarray(self.yaw)[w])
        span = self.times[w.stop - 1] - self.times[w.start]
        travel = base[-1, :2] - base[0, :2]
        c, s = math.cos(yaw[0]), math.sin(yaw[0])
        heading = np.array([c * travel[0] + s * travel[1], -s * travel[0] + c * travel[1]])
        return np.array([*(heading / span), (yaw[-1] - yaw[0]) / span])


def run_walk(commands: list[tuple[float, tuple[float, float, float]]], duration_s: float, *,
             stop_at_s: float | None = None, control_period_s: float = 1e-3,
             pushes: list[Push] = (), gait: GaitParameters | None = None,
             plant: Plant | str = "menagerie", limits: VelocityLimits | None = None) -> WalkRun:
    """Stand 0.3 s, start walking, send each ``(time [s], (forward, lateral, yaw rate))`` at
    its time (since the walk's start), ask for a stop at ``stop_at_s``, run ``duration_s``
    (or until DONE after a stop). Pushes' times are since the walk's start too."""
    controller = WholeBodyController(solver={"control_period_s": control_period_s})
    loop = ControlLoop.simulated(controller=controller, control_period_s=control_period_s,
                                 plant=plant)
    settle(loop, 0.3)
    t0 = loop.sim.time_s
    loop.hooks.append(PushSchedule(loop.sim, [
        Push(at_s=p.at_s + t0, force_n=p.force_n, duration_s=p.duration_s,
             direction_deg=p.direction_deg, relative_to_heading=True) for p in pushes]))
    walking = Walking(controller, gait=gait, limits=limits)
    walking.start(t0)
    run = WalkRun(walking=walking, loop=loop)
    pending = sorted(commands)
    wall = time.perf_counter()
    while True:
        now = loop.sim.time_s
        elapsed = now - t0
        if elapsed >= duration_s or run.done_s is not None:
            break
        while pending and pending[0][0] <= elapsed + 1e-9:
            walking.set_velocity(*pending.pop(0)[1])
        if stop_at_s is not None and run.stop_s is None and elapsed >= stop_at_s - 1e-9:
            walking.request_stop(now)
            run.stop_s = elapsed
        q, v = loop.read_state()
        phase = walking.advance(now)
        out = loop.command(q, v)
        loop.robot.write_command(out)
        for hook in loop.hooks:
            hook(loop, out)
        if out.status.name != "OK":
            run.failures += 1
        true_q = loop.true_state()[0]
        run.times.append(elapsed)
        run.base.append(true_q[:3].copy())
        run.yaw.append(yaw_of(true_q))
        run.estimated.append(q[:3].copy())
        run.phases.append(phase)
        if phase is WalkPhase.DONE and run.done_s is None:
            run.done_s = elapsed
        if true_q[2] < FALLEN_Z_M:
            run.fell = True
            break
    run.wall_s = time.perf_counter() - wall
    return run


__all__ = ["WalkRun", "run_walk", "tick", "yaw_of"]
