"""Walking: speed tracking, pushes while trotting, the tick's cost and the loop's real-time factor.

Run ``python -m benchmarks.walking [--quick] [--json PATH]``.

Every run is a :class:`sim.episode.Episode` with a ``walk`` goal (the Walk action, as
``go2-wbc walk`` and ``cmd_vel`` drive :class:`wbc.locomotion.Walking`), run by
:class:`sim.episode_runner.EpisodeRunner` on the default ``menagerie`` plant with the ``go2``
sensors, and measured tick by tick on the simulator's truth (:class:`WalkTrace`):

1. Speed tracking: forward 0.5 and 1.0 m/s, lateral 0.3 m/s, yaw 1.0 rad/s and a combined
   command, each for :data:`WALK_S` (10 s), on the estimate and on the truth at 1 kHz, and
   forward 0.5 m/s and the combined command on the estimate at 500 Hz. The measured
   velocity is the truth's in the heading frame (:func:`sim.gait_view.heading_velocities`),
   averaged over the walking phase from :data:`SETTLE_INTO_WALK_S` after it began to the
   stop's request; each commanded component's error relative to it, the yaw drift (heading
   change less the commanded turn) and the base height's spread over that window.
2. Pushes while trotting at 0.5 m/s: :data:`PUSH_IMPULSE_NS` on the base in 8 directions
   relative to the heading (0 forward, 90 left), each at a seeded random instant of the
   walk (:func:`push_instants`), on the estimate: fell or not, lowest base, largest tilt.
3. The tick's cost while walking, at 1 kHz on the estimate and on the truth: the walking
   loop and the same robot standing, in one process, taking turns of 100 ticks
   (:func:`benchmarks.walking_lockstep.lockstep`; controller, actions, whole tick on the
   wall clock: median and p99 over the ticks of the walking phase, and the ratio of each
   turn's median to the standing turn's), the walking tick again on the thread's CPU time
   (``time.thread_time``: what other processes on a loaded machine do not add), then the
   walk and the standing untimed for the loop's real-time factor (sim time over wall time)
   and its sim time over the process's CPU time (the real-time factor it would have with a
   core to itself).

A run fell when its base came down to ``benchmarks.robustness.FALLEN_HEIGHT_M`` or ended
below standing height or tilted beyond the balance watch's limit. Every run is seeded and in
simulated time; the timings are wall-clock and depend on the machine's load (the report
states it). ``--quick`` walks 3 s, tracks forward 0.5 m/s and yaw 1 rad/s, pushes in 2
directions.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from actions.go2.go2_interfaces import WalkGoal
from actions.go2.robot_context import STANDING_HEIGHT_M, TILT_LIMIT_DEG, tilt_deg
from benchmarks.reporting import machine, run_and_report
from benchmarks.robustness import FALLEN_HEIGHT_M
from benchmarks.timed_ticks import TimedTicks, stats_us
from benchmarks.walking_lockstep import lockstep
from benchmarks.walking_report import format_report
from sim.control_loop import ControlLoop
from sim.disturbances import Push
from sim.episode import Episode
from sim.episode_runner import EpisodeRunner
from sim.gait_view import heading_velocities, walking_motion
from wbc.controller.control_output import ControlOutput
from wbc.locomotion.walking import Walking

#: ``(name, (forward [m/s], lateral [m/s], yaw rate [rad/s]))`` of the speed-tracking runs.
SPEED_CASES: tuple[tuple[str, tuple[float, float, float]], ...] = (
    ("forward 0.5 m/s", (0.5, 0.0, 0.0)),
    ("forward 1.0 m/s", (1.0, 0.0, 0.0)),
    ("lateral 0.3 m/s", (0.0, 0.3, 0.0)),
    ("yaw 1.0 rad/s", (0.0, 0.0, 1.0)),
    ("combined", (0.5, 0.15, 0.5)),
)
QUICK_SPEED_CASES = (SPEED_CASES[0], SPEED_CASES[3])
#: The cases also run at the GO2's usual 500 Hz (on the estimate; full mode).
SLOW_RATE_CASES = (SPEED_CASES[0], SPEED_CASES[4])
#: How long [s] each walk goal walks (quick: :data:`QUICK_WALK_S`).
WALK_S, QUICK_WALK_S = 10.0, 3.0
#: The mean velocity is taken from this long [s] after the walking phase began (the gait
#: has then reached its command).
SETTLE_INTO_WALK_S = 1.0
#: The pushes: impulse [N s] as a force over a duration [s], the walking velocity [m/s].
PUSH_IMPULSE_NS, PUSH_DURATION_S, PUSH_SPEED_MPS = 5.0, 0.1, 0.5
PUSH_DIRECTIONS_DEG = tuple(range(0, 360, 45))
QUICK_PUSH_DIRECTIONS_DEG = (90, 180)
#: Pushes land at seeded instants this far [s] into the walk (after the start-up), and
#: the walk goes on at least :data:`PUSH_RECOVERY_S` after each.
PUSH_WINDOW_S, PUSH_RECOVERY_S, PUSH_SEED = (1.5, 4.0), 2.0, 31
#: The timed runs: 1 kHz, forward 0.5 m/s for this long [s].
TIMING_PERIOD_S, TIMING_WALK_S, QUICK_TIMING_WALK_S = 1e-3, 6.0, 3.0
#: Rounds of the real-time factors (a walk, then standing as long): the median of each.
RTF_ROUNDS, QUICK_RTF_ROUNDS = 5, 3
STATES = ("estimate", "truth")
#: The packages whose versions the report lists.
PACKAGES = ("mujoco", "numpy", "numba", "pin", "daqp")
#: The robot stands this long [s] before the goal (the default episode's settle).
SETTLE_S = 0.3


class WalkTrace:
    """A loop hook: per tick, the sim time, the walking motion's phase, the truth and the
    controller's state, the measured foot forces (the robot's weight carried or not)."""

    def __init__(self) -> None:
        self.t_s: list[float] = []
        self.phase: list[str] = []
        self.q_true: list[np.ndarray] = []
        self.v_true: list[np.ndarray] = []
        self.q: list[np.ndarray] = []
        self.v: list[np.ndarray] = []

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        walking = walking_motion(loop)
        self.t_s.append(loop.context.now_s)
        self.phase.append(str(walking.phase) if isinstance(walking, Walking) else "")
        q, v = loop.true_state()  # after this tick's physics: the next tick's instant
        self.q_true.append(q.copy())
        self.v_true.append(v.copy())
        self.q.append(np.array(loop.context.q))
        self.v.append(np.array(loop.context.v))

    def arrays(self) -> dict[str, np.ndarray]:
        """The rows as arrays (N ticks)."""
        return {"t_s": np.array(self.t_s), "phase": np.array(self.phase, dtype=str),
                "q_true": np.array(self.q_true), "v_true": np.array(self.v_true),
                "q": np.array(self.q), "v": np.array(self.v)}


@dataclass(frozen=True)
class WalkRun:
    """One walk goal's episode: its command, state source, rate and pushes."""

    command: tuple[float, float, float]
    walk_s: float
    state: str = "estimate"
    control_period_s: float = 1e-3
    pushes: tuple[Push, ...] = ()
    #: Sim time [s] spun after the result (the trace sees the robot settle; the real-time
    #: factor's run spins none: the runner's wall time includes it, its sim time does not).
    after_s: float = 0.5

    def episode(self) -> Episode:
        forward, lateral, yaw_rate = self.command
        goal = WalkGoal(forward_mps=forward, lateral_mps=lateral, yaw_rate_radps=yaw_rate,
                        duration_s=self.walk_s)
        return Episode(action="walk", goal=goal, state=self.state, settle_s=SETTLE_S,
                       control_period_s=self.control_period_s, pushes=self.pushes,
                       after_s=self.after_s)


def measure(trace: dict[str, np.ndarray], command: Sequence[float]) -> dict[str, Any]:
    """What a walk did, on the truth: the mean velocity over the steady window against the
    command, the yaw drift, the base height's spread, fell or not.

    Args:
        trace: :meth:`WalkTrace.arrays`.
        command: The commanded forward, lateral [m/s] and yaw rate [rad/s].
    """
    t, phase = trace["t_s"], trace["phase"]
    q_true = trace["q_true"]
    walking = np.flatnonzero(phase == "walking")
    heights = q_true[:, 2]
    tilts = np.array([tilt_deg(q) for q in q_true])
    out: dict[str, Any] = {
        "min_height_m": float(heights.min()), "final_height_m": float(heights[-1]),
        "max_tilt_deg": float(tilts.max()), "final_tilt_deg": float(tilts[-1]),
        "walking_s": float(t[walking[-1]] - t[walking[0]]) if walking.size else 0.0}
    out["fell"] = bool(out["min_height_m"] < FALLEN_HEIGHT_M
                       or out["final_height_m"] < STANDING_HEIGHT_M
                       or out["final_tilt_deg"] > TILT_LIMIT_DEG)
    steady = walking[t[walking] >= t[walking[0]] + SETTLE_INTO_WALK_S] if walking.size else walking
    if steady.size < 2:
        return {**out, "steady_s": 0.0, "measured": [math.nan] * 3,
                "estimated": [math.nan] * 3, "relative_error": [math.nan] * 3,
                "yaw_drift_deg": math.nan, "height_mean_m": math.nan, "height_range_mm": math.nan}
    truth = heading_velocities(q_true[steady], trace["v_true"][steady]).mean(axis=0)
    estimate = heading_velocities(trace["q"][steady], trace["v"][steady]).mean(axis=0)
    command = np.asarray(command, dtype=float)
    # Relative where commanded; an uncommanded component's error is its value (same units).
    relative = np.where(command != 0.0, (truth - command) / np.where(command != 0.0, command,
                                                                     1.0), truth)
    quat = q_true[steady, 3:7]
    heading = np.unwrap(np.arctan2(2 * (quat[:, 3] * quat[:, 2] + quat[:, 0] * quat[:, 1]),
                                   1 - 2 * (quat[:, 1] ** 2 + quat[:, 2] ** 2)))
    span_s = float(t[steady[-1]] - t[steady[0]])
    drift = heading[-1] - heading[0] - command[2] * span_s
    window = heights[steady]
    return {**out, "steady_s": span_s, "measured": truth.tolist(), "estimated": estimate.tolist(),
            "relative_error": relative.tolist(), "yaw_drift_deg": math.degrees(drift),
            "height_mean_m": float(window.mean()),
            "height_range_mm": float((window.max() - window.min()) * 1e3)}


def run_walk(run: WalkRun, *, clock: Callable[[], float] | None = None,
             traced: bool = True) -> dict[str, Any]:
    """One episode, traced (:func:`measure`); with a ``clock``, its ticks run as
    :class:`TimedTicks` on that clock and their times over the walking phase come back too;
    ``traced=False``: no trace hook (the loop as ``go2-wbc`` runs it, for its real-time
    factor), and only the end state's height and tilt are measured."""
    trace = WalkTrace()
    runner = EpisodeRunner(run.episode(), hooks=[trace] if traced else [])
    ticks = TimedTicks(runner.loop, clock=clock) if clock is not None else None
    result = runner.run(tick=ticks)
    out: dict[str, Any] = {
        "status": result.status, "message": result.message, "sim_s": result.sim_s,
        "wall_s": result.wall_s,
        "real_time_factor": result.sim_s / max(result.wall_s, 1e-9),
        "sim_over_cpu": result.sim_s / max(result.cpu_s, 1e-9),
        "cpu_share": result.cpu_s / max(result.wall_s, 1e-9), "ticks": result.ticks}
    if not traced:
        q, _ = runner.loop.true_state()
        return {**out, "final_height_m": float(q[2]), "final_tilt_deg": tilt_deg(q),
                "fell": bool(q[2] < STANDING_HEIGHT_M or tilt_deg(q) > TILT_LIMIT_DEG)}
    arrays = trace.arrays()
    out.update(measure(arrays, run.command))
    if ticks is not None:
        # Both see the ticks from the goal's sending to its result (the trace also the
        # episode's after_s, which the runner spins untimed).
        walking = arrays["phase"][:len(ticks.samples["tick"])] == "walking"
        out["walking_ticks_us"] = {
            part: stats_us(np.asarray(ticks.samples[part])[walking])
            for part in ("controller", "actions", "estimator", "physics", "tick")}
    return out


def run_standing(state: str, seconds: float, *,
                 clock: Callable[[], float] | None = None) -> dict[str, Any]:
    """The yardstick of the timing rows: the robot standing ``seconds`` at 1 kHz (no goal),
    its ticks timed on ``clock`` (every tick), or untimed for the real-time factor."""
    runner = EpisodeRunner(Episode(action=None, state=state, settle_s=SETTLE_S,
                                   control_period_s=TIMING_PERIOD_S, after_s=seconds))
    ticks = TimedTicks(runner.loop, clock=clock) if clock is not None else None
    result = runner.run(tick=ticks)
    out: dict[str, Any] = {
        "sim_s": result.sim_s, "real_time_factor": result.sim_s / max(result.wall_s, 1e-9),
        "sim_over_cpu": result.sim_s / max(result.cpu_s, 1e-9)}
    if ticks is not None:
        out["ticks_us"] = {part: stats_us(ticks.samples[part])
                           for part in ("controller", "actions", "estimator", "physics", "tick")}
    return out


def push_instants(count: int, walk_s: float, seed: int = PUSH_SEED) -> list[float]:
    """``count`` seeded instants [s into the walk] in :data:`PUSH_WINDOW_S`, each leaving
    :data:`PUSH_RECOVERY_S` of walking after it."""
    low, high = PUSH_WINDOW_S[0], min(PUSH_WINDOW_S[1], walk_s - PUSH_RECOVERY_S)
    rng = np.random.default_rng(seed)
    return [round(float(x), 3) for x in rng.uniform(low, max(low, high), size=count)]


#: The benchmark's parts, in the order they run.
PARTS = ("tracking", "pushes", "timing")


def tracking_runs(quick: bool, log: Callable[[str], None]) -> list[dict[str, Any]]:
    """The speed-tracking walks (part 1)."""
    walk_s = QUICK_WALK_S if quick else WALK_S
    plan = [(case, state, 1e-3) for case in (QUICK_SPEED_CASES if quick else SPEED_CASES)
            for state in STATES]
    plan += [] if quick else [(case, "estimate", 2e-3) for case in SLOW_RATE_CASES]
    rows = []
    for (name, command), state, period_s in plan:
        log(f"speed tracking: {name} on the {state} at {1 / period_s:g} Hz")
        rows.append({"name": name, "command": list(command), "state": state,
                     "control_rate_hz": 1.0 / period_s,
                     **run_walk(WalkRun(command, walk_s, state=state,
                                        control_period_s=period_s))})
    return rows


def push_runs(quick: bool, log: Callable[[str], None]) -> dict[str, Any]:
    """The pushes while trotting (part 2)."""
    walk_s = QUICK_WALK_S + 1.0 if quick else max(WALK_S, PUSH_WINDOW_S[1] + PUSH_RECOVERY_S)
    directions = QUICK_PUSH_DIRECTIONS_DEG if quick else PUSH_DIRECTIONS_DEG
    rows = []
    for direction, into_walk_s in zip(directions, push_instants(len(directions), walk_s),
                                      strict=True):
        # The walk goal is sent at SETTLE_S; its walking starts after a short start-up.
        push = Push(at_s=SETTLE_S + into_walk_s, force_n=PUSH_IMPULSE_NS / PUSH_DURATION_S,
                    duration_s=PUSH_DURATION_S, direction_deg=direction,
                    relative_to_heading=True)
        log(f"push {PUSH_IMPULSE_NS:g} N s toward {direction} deg at {push.at_s:g} s")
        outcome = run_walk(WalkRun((PUSH_SPEED_MPS, 0.0, 0.0), walk_s, pushes=(push,)))
        rows.append({"direction_deg": direction, "at_s": push.at_s, **outcome})
    return {"impulse_ns": PUSH_IMPULSE_NS, "duration_s": PUSH_DURATION_S,
            "speed_mps": PUSH_SPEED_MPS, "walk_s": walk_s, "seed": PUSH_SEED, "runs": rows,
            "fell": sum(p["fell"] for p in rows)}


def timing_runs(quick: bool, log: Callable[[str], None]) -> dict[str, Any]:
    """The tick's cost and the real-time factors, walking and standing (part 3)."""
    timing_s = QUICK_TIMING_WALK_S if quick else TIMING_WALK_S
    rows = []
    for state in STATES:
        log(f"the tick at 1 kHz on the {state}: walking and standing in lockstep")
        timed = WalkRun((PUSH_SPEED_MPS, 0.0, 0.0), timing_s, state=state,
                        control_period_s=TIMING_PERIOD_S)
        turns = lockstep(timed.episode(), settle_s=SETTLE_S, walk_s=timing_s)
        log(f"the tick at 1 kHz on the {state}: CPU time, then the real-time factors")
        cpu = run_walk(timed, clock=time.thread_time)
        walks, stands = [], []
        for _ in range(QUICK_RTF_ROUNDS if quick else RTF_ROUNDS):  # alternating: a host's
            walks.append(run_walk(replace(timed, after_s=0.0), traced=False))  # drift hits
            stands.append(run_standing(state, timing_s))                       # both
        failed = [w for w in walks if w["status"] != "SUCCEEDED"]
        rows.append({"state": state, "status": (failed or walks)[0]["status"],
                     "fell": any(w["fell"] for w in walks), "lockstep": turns,
                     "walking_ticks_cpu_us": cpu["walking_ticks_us"],
                     "real_time_factor": _median(walks, "real_time_factor"),
                     "sim_over_cpu": _median(walks, "sim_over_cpu"),
                     "cpu_share": _median(walks, "cpu_share"), "sim_s": walks[0]["sim_s"],
                     "standing_real_time_factor": _median(stands, "real_time_factor"),
                     "standing_sim_over_cpu": _median(stands, "sim_over_cpu"),
                     "rounds": [{"walking": w["real_time_factor"],
                                 "standing": st["real_time_factor"]}
                                for w, st in zip(walks, stands, strict=True)]})
    return {"control_rate_hz": 1.0 / TIMING_PERIOD_S, "walk_s": timing_s, "runs": rows}


def _median(runs: list[dict[str, Any]], key: str) -> float:
    return float(np.median([run[key] for run in runs]))


def run(*, quick: bool = False, parts: Sequence[str] = PARTS,
        log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """The ``parts`` asked for (all by default); the report as a dict."""
    report: dict[str, Any] = {
        "machine": machine(PACKAGES, with_platform=False),
        "mode": "quick" if quick else "full",
        "walk_s": QUICK_WALK_S if quick else WALK_S,
        "settle_into_walk_s": SETTLE_INTO_WALK_S}
    for part, runs in (("tracking", tracking_runs), ("pushes", push_runs),
                       ("timing", timing_runs)):
        if part in parts:
            report[part] = runs(quick, log)
    return report


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.walking",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"walk {QUICK_WALK_S:g} s, two speed cases, two push directions")
    parser.add_argument("--only", choices=PARTS, action="append", metavar="PART",
                        help=f"run only this part, repeatable: {', '.join(PARTS)} "
                             "(default: all)")
    parser.add_argument("--json", type=Path, default=Path("out/walking.json"),
                        help="where to write the report (default: out/walking.json)")
    args = parser.parse_args(argv)
    return run_and_report(lambda log: run(quick=args.quick, parts=args.only or PARTS, log=log),
                          format_report, args.json)


if __name__ == "__main__":
    raise SystemExit(main())
