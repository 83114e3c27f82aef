"""Timing a controller through a lift of FR in closed loop, tick by tick, for the QP benchmark.

Every run drives a fresh loop of the default episode (:func:`sim.episode_loop.build_loop`:
the default plant, sensors and estimator) by hand, read, step, write, through a
:class:`wbc.LegLift` (no action runner: the controller's tick alone is timed), after
:data:`WARMUP_TICKS` standing ticks that no statistic counts.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from actions.go2.high_five_behaviour import PHASE_NAMES
from sim.episode import Episode, episode_default
from sim.episode_loop import build_loop
from sim.run_recorder import MetricsHook
from wbc.controller.balance_controller import BalanceController
from wbc.controller.placo_controller import PlacoController
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.motions.leg_lift import LegLift, LegLiftTiming, LiftPhase

#: The lift: FR to the default episode's height [m], held as long as its goal's [s]; the
#: quick mode's hold [s].
LEG, HEIGHT_M = "FR", episode_default("goal").target_height
HOLD_S, QUICK_HOLD_S = float(episode_default("goal").hold_seconds), 0.3
WARMUP_TICKS = 200
#: Stages of ControlOutput.timings (our controller computes task terms inside "assembly").
STAGES = ("model", "assembly", "solve", "total")
PLACO = "placo"
DEFAULT = "default"
#: Quick timing episodes: a faster shift and unload, stopped after this much lift time [s].
QUICK_LIFT_S = 1.0
#: Durations are off the 1 ms tick grid: a tick landing a rounding error short of a phase's
#: end makes LegLift's ramp overshoot and ask for a -1e-13 N force bound (a ValueError).
QUICK_TIMING = LegLiftTiming(shift_s=0.5005, unload_s=0.3005)
#: The scaling runs only need to reach the hold: they get there faster.
SCALING_TIMING = LegLiftTiming(shift_s=0.5005, unload_s=0.3005, raise_s=0.8005)


@dataclass
class TimedLift:
    """What one closed-loop run recorded (timed ticks only in ``timings``)."""

    timings: dict[str, list[float]] = field(default_factory=lambda: {s: [] for s in STAGES})
    #: CPU time [s] of the calling thread in ``controller.step`` (preemption excluded).
    cpu_times: list[float] = field(default_factory=list)
    violations: list[tuple[float, float]] = field(default_factory=list)
    failures: int = 0
    ticks: int = 0
    sim_s: float = 0.0
    control_wall_s: float = 0.0
    #: Process CPU time over wall time of the episode: well below 1, other processes took
    #: the CPU and the tail of the timings shows their preemptions, not the solver.
    cpu_share: float = 1.0
    metrics: dict[str, float] = field(default_factory=dict)


class LiftLoop:
    """``controller`` on a fresh loop of the default episode, driven by hand: warm-up ticks
    standing, then a lift of FR (:meth:`start_lift`), one :meth:`tick` a control period."""

    def __init__(self, controller: BalanceController):
        self.controller = controller
        self.loop = build_loop(Episode(), controller)  # resets the controller
        self.lift: LegLift | None = None
        self.start_s = 0.0

    def warm_up(self, ticks: int = WARMUP_TICKS) -> None:
        """Untimed ticks standing."""
        loop, step = self.loop, self.controller.step
        for _ in range(ticks):
            loop.robot.write_command(step(*loop.read_state()))

    def start_lift(self, *, hold_s: float, timing: LegLiftTiming | None) -> LegLift:
        """Start lifting FR now, holding it ``hold_s`` [s] (``timing``: the phases')."""
        self.lift = LegLift(self.controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s,
                            timing=timing)
        self.start_s = self.loop.sim.time_s
        self.lift.start(self.start_s)
        return self.lift

    def running(self, stop_after_s: float | None = None) -> bool:
        """The lift is not done (nor ``stop_after_s`` [s] old)."""
        return self.lift.phase is not LiftPhase.DONE and (
            stop_after_s is None or self.loop.sim.time_s - self.start_s < stop_after_s - 1e-9)

    def tick(self) -> tuple[LiftPhase | None, np.ndarray, np.ndarray, Any, float]:
        """One control period: the lift's phase (``None`` before it), the state read, the
        command sent, and the CPU time [s] of ``controller.step``."""
        loop = self.loop
        phase = None if self.lift is None else self.lift.advance(loop.sim.time_s)
        q, v = loop.read_state()
        out, cpu_s = timed_step(self.controller, q, v)
        loop.robot.write_command(out)
        return phase, q, v, out, cpu_s


def solution_violations(controller: BalanceController, out: Any) -> tuple[float, float] | None:
    """Largest equality and inequality violation of the QP solution behind ``out``.

    :class:`WholeBodyController`: its ``last_solution`` checked against its ``problem``;
    :class:`PlacoController`: its ``solution_violations()``. Call right after ``step``,
    before the references change. ``None`` for a fallback tick.
    """
    if not out.ok:
        return None
    if isinstance(controller, WholeBodyController):
        return controller.problem.violations(controller.last_solution)
    return controller.solution_violations()  # type: ignore[attr-defined]


def timed_step(controller: BalanceController, q: np.ndarray, v: np.ndarray
               ) -> tuple[Any, float]:
    """``controller.step(q, v)`` and the CPU time [s] the calling thread spent in it."""
    cpu = time.thread_time()
    out = controller.step(q, v)
    return out, time.thread_time() - cpu


def _record(run: TimedLift, controller: BalanceController, out: Any, cpu_s: float) -> None:
    run.ticks += 1
    run.cpu_times.append(cpu_s)
    for stage in STAGES:
        run.timings[stage].append(out.timings.get(stage, np.nan))
    if not out.ok:
        run.failures += 1
    violation = solution_violations(controller, out)
    if violation is not None:
        run.violations.append(violation)


def run_episode(controller: BalanceController, *, hold_s: float, stop_after_s: float | None,
                timing: LegLiftTiming | None = None, quality: bool = False) -> TimedLift:
    """Warm up standing, then lift FR in closed loop; record every lift tick.

    Args:
        controller: A fresh controller.
        hold_s: Hold time of the lift [s].
        stop_after_s: Stop after this much lift time [s] (``None``: run the whole lift).
        timing: The lift's phase durations (LegLift's defaults when ``None``).
        quality: Also collect the episode-table metrics with
            :class:`sim.episode_metrics.EpisodeMetrics` (its MuJoCo queries are excluded
            from the real-time factor).
    """
    clocks = time.process_time(), time.perf_counter()
    wall = time.perf_counter()
    lift_loop = LiftLoop(controller)
    run = TimedLift()
    lift_loop.warm_up()
    run.control_wall_s += time.perf_counter() - wall
    lift = lift_loop.start_lift(hold_s=hold_s, timing=timing)
    phase_name = [""]
    loop = lift_loop.loop
    meter = MetricsHook(loop, lambda: phase_name[0], LEG) if quality else None
    while lift_loop.running(stop_after_s):
        wall = time.perf_counter()
        phase, _, _, out, cpu_s = lift_loop.tick()
        run.control_wall_s += time.perf_counter() - wall
        _record(run, controller, out, cpu_s)
        if meter is not None:  # measured on the truth
            phase_name[0] = PHASE_NAMES.get(phase, "")
            meter(loop, out)
    run.sim_s = loop.sim.time_s
    run.cpu_share = ((time.process_time() - clocks[0])
                     / max(time.perf_counter() - clocks[1], 1e-9))
    if meter is not None:
        run.metrics = meter.metrics.summary(run.control_wall_s).as_dict()
        run.metrics["lift_completed"] = lift.phase is LiftPhase.DONE
    return run


def stats_us(samples: Sequence[float]) -> dict[str, float | None]:
    """Median, p90, p99 and max [us] of the finite ``samples`` [s] (``None`` without any)."""
    values = np.asarray(samples, dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"median": None, "p90": None, "p99": None, "max": None}
    return {"median": 1e6 * float(np.median(values)), "p90": 1e6 * float(np.percentile(values, 90)),
            "p99": 1e6 * float(np.percentile(values, 99)), "max": 1e6 * float(values.max())}


# ---------------------------------------------------------------------------- recorded states


@dataclass
class Recording:
    """The measured states of one closed-loop lift, and when they were measured."""

    q: np.ndarray
    v: np.ndarray
    t: np.ndarray


def record_lift(*, hold_s: float, timing: LegLiftTiming | None) -> Recording:
    """The default controller lifts FR on the default plant and sensors; every lift tick's
    estimated state (what the controller read)."""
    lift_loop = LiftLoop(WholeBodyController())
    lift_loop.warm_up()
    lift_loop.start_lift(hold_s=hold_s, timing=timing)
    qs, vs, ts = [], [], []
    while lift_loop.running():
        ts.append(lift_loop.loop.sim.time_s)
        _, q, v, _, _ = lift_loop.tick()
        qs.append(q)
        vs.append(v)
    return Recording(np.array(qs), np.array(vs), np.array(ts))


def replay(recording: Recording, factory: Callable[[], BalanceController], *,
           hold_s: float, timing: LegLiftTiming | None, passes: int = 2) -> dict[str, Any]:
    """Tick times of a fresh controller fed the recorded states (no simulation between
    ticks: the controller alone, its caches warm). The lift's targets follow the recorded
    clock; the last of ``passes`` passes is measured."""
    samples: list[float] = []
    stages: dict[str, list[float]] = {}
    for _ in range(passes):
        controller = factory()
        controller.reset(recording.q[0])
        lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s, timing=timing)
        lift.start(float(recording.t[0]))
        samples, stages = [], {}
        for q, v, t in zip(recording.q, recording.v, recording.t):
            lift.advance(float(t))
            start = time.perf_counter()
            out = controller.step(q, v)
            samples.append(time.perf_counter() - start)
            for stage, seconds in out.timings.items():
                stages.setdefault(stage, []).append(seconds)
    return {**{f"{k}_us": value for k, value in stats_us(samples).items()},
            "stage_median_us": {k: 1e6 * float(np.median(v)) for k, v in stages.items()},
            "ticks": len(samples)}


def run_recorded(*, hold_s: float, timing: LegLiftTiming | None) -> dict[str, Any]:
    """Default controller (elimination on and off, DAQP cold and hot) and PlaCo, each alone
    on the same recorded lift."""
    recording = record_lift(hold_s=hold_s, timing=timing)
    rows = {}
    for name, factory in ((DEFAULT, WholeBodyController),
                          ("daqp-hot (reduced QP)",
                           lambda: WholeBodyController(solver={"backend": "daqp-hot"})),
                          ("daqp (full QP)",
                           lambda: WholeBodyController(solver={"eliminate_dynamics": False})),
                          (PLACO, PlacoController)):
        rows[name] = replay(recording, factory, hold_s=hold_s, timing=timing)
    return {"ticks": len(recording.t), "rows": rows}


# ---------------------------------------------------------------------------- scaling, lockstep


def qp_size(controller: BalanceController) -> str:
    """The QP the controller solves now: variables and rows (and what it was reduced from)."""
    if isinstance(controller, PlacoController):
        p = controller.solver.problem
        return (f"{p.n_variables} var ({p.free_variables} free), "
                f"{p.n_inequalities} ineq")
    builder = controller.builder  # type: ignore[attr-defined]
    full, solved = builder.problem, builder.reduced_problem
    if solved is None or not builder.reduced:
        return f"{full.n} var, {full.m} rows + bounds"
    return f"{solved.n} var, {solved.m} rows (reduced from {full.n} var, {full.m} rows)"


def _block_ratios(samples: list[float], reference: list[float], block_ticks: int
                  ) -> list[float]:
    """Median of each turn of ``samples`` over the median of the same turn of ``reference``."""
    blocks = min(len(samples), len(reference)) // block_ticks
    return [float(np.median(samples[i * block_ticks:(i + 1) * block_ticks])
                  / np.median(reference[i * block_ticks:(i + 1) * block_ticks]))
            for i in range(blocks)]


def run_scaling(ticks: int, *, block_ticks: int = 50,
                controllers: Sequence[tuple[str, Callable[[], BalanceController]]] = (
                    (DEFAULT, WholeBodyController), (PLACO, PlacoController)),
                ) -> list[dict[str, Any]]:
    """Tick times standing on four feet, then with FR held up (swing task on, then off),
    every controller in turns.

    Each controller drives its own loop; every scenario is reached by all of them (untimed),
    then they take turns of ``block_ticks`` ticks on it until each has ``ticks`` timed ticks,
    so that the machine's drift between episodes falls on all alike (as in
    :func:`run_head_to_head`). Rows: one a controller and scenario, with its ratio of medians
    to the last controller's (PlaCo's) on the same scenario and the p10/p50/p90 of the
    per-turn ratios.
    """
    if ticks < block_ticks or block_ticks < 1:
        raise ValueError(f"run_scaling: ticks={ticks} and block_ticks={block_ticks}; valid: "
                         "1 <= block_ticks <= ticks")
    loops = {name: LiftLoop(factory()) for name, factory in controllers}

    def untimed(lift_loop: LiftLoop, n: int) -> None:
        for _ in range(n):
            lift_loop.tick()

    def in_turns() -> dict[str, tuple[list[float], list[float]]]:
        samples: dict[str, tuple[list[float], list[float]]] = {n: ([], []) for n in loops}
        for _ in range(0, ticks, block_ticks):
            for name, lift_loop in loops.items():
                times, cpu_times = samples[name]
                for _ in range(min(block_ticks, ticks - len(times))):
                    _, _, _, out, cpu_s = lift_loop.tick()
                    times.append(out.timings["total"])
                    cpu_times.append(cpu_s)
        return samples

    for lift_loop in loops.values():
        untimed(lift_loop, WARMUP_TICKS)
    scenarios = [("4 contacts, standing", in_turns(),
                  {n: qp_size(lp.controller) for n, lp in loops.items()})]
    for lift_loop in loops.values():
        lift = lift_loop.start_lift(hold_s=1e3, timing=SCALING_TIMING)
        while lift.phase is not LiftPhase.HOLDING:
            untimed(lift_loop, 1)
        untimed(lift_loop, ticks)  # settle at the hold
    size3 = {n: qp_size(lp.controller) for n, lp in loops.items()}
    scenarios.append(("3 contacts + swing-foot task (FR held up)", in_turns(), size3))
    for lift_loop in loops.values():
        lift_loop.controller.set_foot_weight(LEG, 0.0)
    scenarios.append(("3 contacts, swing-foot task weight 0", in_turns(), size3))

    reference = controllers[-1][0]
    rows = []
    for name in loops:
        for label, samples, sizes in scenarios:
            times, cpu_times = samples[name]
            ref = samples[reference][0]
            ratios = _block_ratios(times, ref, block_ticks)
            rows.append({"controller": name, "scenario": label, "qp": sizes[name],
                         "ticks": len(times), "block_ticks": block_ticks,
                         **{f"{k}_us": v for k, v in stats_us(times).items()},
                         "cpu_median_us": stats_us(cpu_times)["median"],
                         "ratio_to_placo": float(np.median(times) / np.median(ref)),
                         "block_ratio_p10_p50_p90": [float(np.percentile(ratios, k))
                                                     for k in (10, 50, 90)]})
    return rows


def run_head_to_head(*, block_ticks: int, hold_s: float, stop_after_s: float | None,
                     timing: LegLiftTiming | None) -> dict[str, Any]:
    """The default controller and PlaCo through the same lift in lockstep.

    Each drives its own simulation; they take turns every ``block_ticks`` ticks. On a shared
    or virtual machine the speed drifts from one episode to the next by more than the two
    controllers differ (medians of single episodes here moved by 2x); in lockstep both see
    the same drift, so the ratio of their medians measures the controllers.
    """
    runs: dict[str, tuple[LiftLoop, list[float]]] = {}
    for name, factory in ((DEFAULT, WholeBodyController), (PLACO, PlacoController)):
        lift_loop = LiftLoop(factory())
        lift_loop.warm_up()
        lift_loop.start_lift(hold_s=hold_s, timing=timing)
        runs[name] = (lift_loop, [])

    while any(lift_loop.running(stop_after_s) for lift_loop, _ in runs.values()):
        for lift_loop, samples in runs.values():
            for _ in range(block_ticks):
                if not lift_loop.running(stop_after_s):
                    break
                _, _, _, out, _ = lift_loop.tick()
                samples.append(out.timings["total"])
    default, placo = runs[DEFAULT][1], runs[PLACO][1]
    ratios = _block_ratios(default, placo, block_ticks)
    return {"block_ticks": block_ticks, "default": stats_us(default),
            "placo": stats_us(placo),
            "median_ratio": float(np.median(default) / np.median(placo)),
            "block_ratio_p10_p50_p90": [float(np.percentile(ratios, k)) for k in (10, 50, 90)]}
