"""Per-tick QP timing of every backend and of PlaCo on a closed-loop high five in MuJoCo.

Run ``python -m benchmarks.qp_timing [--quick] [--json PATH] [--plot PATH]``.

Four tables, all measured through the library's public API, every controller reading the
state estimated from the default plant's simulated sensors (the loop's default estimator),
every quality figure measured on the simulator's truth:

1. Backends: one closed-loop episode per backend (200 standing warm-up ticks, excluded from
   the statistics, then a ``LegLift`` of leg FR to 0.40 m at 1 kHz, motor commands to the
   default Menagerie plant). Each tick's ``ControlOutput.timings`` give the stage times; the
   returned QP solution is checked against the problem it solved. The full mode runs the
   whole lift with a 2 s hold; ``--quick`` shifts in 0.5 s, unloads in 0.3 s and stops after 1.0 s of the lift
   (the first 0.2 s of the raise), so that the one-shot OSQP (~4 ms a tick) stays short.
2. Alone, on recorded states: one closed-loop lift's estimated states replayed into fresh
   controllers (the default; DAQP with its hot start; the full QP without the elimination;
   PlaCo), with no simulation between ticks: the controller's own time, caches warm.
3. Scaling: tick time against the number of contacts (four feet standing; three with the
   foot held up) and with the swing-foot task's weight set to zero, for the default
   backend and PlaCo (reaching the hold with faster phases: only the hold is timed).
4. Episode quality of the default backend over a whole lift (hold 2 s, or 0.3 s in quick
   mode): tracking, slip, forces, margins, torques, failures, real-time factor.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import importlib.metadata
import json
import os
import platform
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from actions.go2.high_five_behaviour import PHASE_NAMES
from sim.control_loop import ControlLoop
from sim.run_recorder import MetricsHook
from wbc.backends.backend import available_backends, missing_backends
from wbc.controller.balance_controller import BalanceController
from wbc.controller.controller_config import ControllerConfig
from wbc.controller.placo_controller import PlacoController
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.motions.leg_lift import LegLift, LegLiftTiming, LiftPhase

LEG, HEIGHT_M = "FR", 0.40
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
PACKAGES = ("pin", "placo", "mujoco", "daqp", "osqp", "qpsolvers", "numpy", "proxsuite", "piqp",
            "quadprog")


@contextlib.contextmanager
def c_stdout_silenced() -> Iterator[None]:
    """Discard what C libraries print on the process's standard output inside the block.

    OSQP 1.x prints "Polishing not needed - no active set detected at optimal point" on
    every solve whose active set is empty, whatever its ``verbose`` setting (its issue 785),
    which would interleave dozens of lines with the report. The episodes run in this one
    thread, so redirecting file descriptor 1 hides nothing else; Python's output is flushed
    before, C's buffers before the descriptor is restored.
    """
    sys.stdout.flush()
    libc = ctypes.CDLL(None)
    saved = os.dup(1)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        libc.fflush(None)
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


@dataclass
class Episode:
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


# ---------------------------------------------------------------------------- measuring


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


def _timed_step(controller: BalanceController, q: np.ndarray, v: np.ndarray
                ) -> tuple[Any, float]:
    """``controller.step(q, v)`` and the CPU time [s] the calling thread spent in it."""
    cpu = time.thread_time()
    out = controller.step(q, v)
    return out, time.thread_time() - cpu


def _record(episode: Episode, controller: BalanceController, out: Any, cpu_s: float) -> None:
    episode.ticks += 1
    episode.cpu_times.append(cpu_s)
    for stage in STAGES:
        episode.timings[stage].append(out.timings.get(stage, np.nan))
    if not out.ok:
        episode.failures += 1
    violation = solution_violations(controller, out)
    if violation is not None:
        episode.violations.append(violation)


def _loop(controller: BalanceController) -> ControlLoop:
    """The default plant and sensors around ``controller``, which reads the estimated state
    (the loop's pieces are driven by hand: read, step, write)."""
    return ControlLoop.simulated(controller=controller)


def run_episode(controller: BalanceController, *, hold_s: float, stop_after_s: float | None,
                timing: LegLiftTiming | None = None, quality: bool = False) -> Episode:
    """Warm up standing, then lift FR to 0.40 m in closed loop; record every lift tick.

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
    loop = _loop(controller)  # resets the controller
    sim, robot = loop.sim, loop.robot
    episode = Episode()
    for _ in range(WARMUP_TICKS):
        robot.write_command(controller.step(*loop.read_state()))
    episode.control_wall_s += time.perf_counter() - wall
    lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s, timing=timing)
    lift.start(sim.time_s)
    start = sim.time_s
    phase_name = [""]
    meter = MetricsHook(loop, lambda: phase_name[0], LEG) if quality else None
    while lift.phase is not LiftPhase.DONE:
        if stop_after_s is not None and sim.time_s - start >= stop_after_s - 1e-9:
            break
        wall = time.perf_counter()
        phase = lift.update(sim.time_s)
        q, v = loop.read_state()
        out, cpu_s = _timed_step(controller, q, v)
        robot.write_command(out)
        episode.control_wall_s += time.perf_counter() - wall
        _record(episode, controller, out, cpu_s)
        if meter is not None:  # measured on the truth
            phase_name[0] = PHASE_NAMES.get(phase, "")
            meter(loop, out)
    episode.sim_s = sim.time_s
    episode.cpu_share = ((time.process_time() - clocks[0])
                         / max(time.perf_counter() - clocks[1], 1e-9))
    if meter is not None:
        episode.metrics = meter.metrics.summary(episode.control_wall_s).as_dict()
        episode.metrics["lift_completed"] = lift.phase is LiftPhase.DONE
    return episode


def _stats_us(samples: Sequence[float]) -> dict[str, float | None]:
    values = np.asarray(samples, dtype=float)
    values = values[np.isfinite(values)]
    if values.size == 0:
        return {"median": None, "p90": None, "p99": None, "max": None}
    return {"median": 1e6 * float(np.median(values)), "p90": 1e6 * float(np.percentile(values, 90)),
            "p99": 1e6 * float(np.percentile(values, 99)), "max": 1e6 * float(values.max())}


def backend_row(name: str, episode: Episode) -> dict[str, Any]:
    """One row of the backend table from an episode."""
    violations = np.array(episode.violations) if episode.violations else np.full((1, 2), np.nan)
    total = _stats_us(episode.timings["total"])
    stages = {s: _stats_us(episode.timings[s])["median"] for s in STAGES[:-1]}
    return {
        "name": name, "skipped": None, "ticks": episode.ticks, "sim_s": episode.sim_s,
        **{f"{k}_us": v for k, v in total.items()},
        "stage_median_us": stages,
        "cpu_median_us": _stats_us(episode.cpu_times)["median"],
        "max_eq_violation": _finite_or_none(np.nanmax(violations[:, 0])),
        "max_ineq_violation": _finite_or_none(np.nanmax(violations[:, 1])),
        "failures": episode.failures,
        "cpu_share": episode.cpu_share,
        "total_samples_us": [round(1e6 * t, 2) for t in episode.timings["total"]],
    }


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


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
    controller = WholeBodyController()
    loop = _loop(controller)
    sim = loop.sim
    for _ in range(WARMUP_TICKS):
        loop.robot.write_command(controller.step(*loop.read_state()))
    lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s, timing=timing)
    lift.start(sim.time_s)
    qs, vs, ts = [], [], []
    while lift.phase is not LiftPhase.DONE:
        lift.update(sim.time_s)
        q, v = loop.read_state()
        qs.append(q)
        vs.append(v)
        ts.append(sim.time_s)
        loop.robot.write_command(controller.step(q, v))
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
            lift.update(float(t))
            start = time.perf_counter()
            out = controller.step(q, v)
            samples.append(time.perf_counter() - start)
            for stage, seconds in out.timings.items():
                stages.setdefault(stage, []).append(seconds)
    return {**{f"{k}_us": value for k, value in _stats_us(samples).items()},
            "stage_median_us": {k: 1e6 * float(np.median(v)) for k, v in stages.items()},
            "ticks": len(samples)}


def run_recorded(*, hold_s: float, timing: LegLiftTiming | None) -> dict[str, Any]:
    """Default controller (elimination on and off, DAQP cold and hot) and PlaCo, each alone
    on the same recorded lift."""
    recording = record_lift(hold_s=hold_s, timing=timing)
    rows = {}
    for name, factory in ((DEFAULT, WholeBodyController),
                          ("daqp-hot (reduced QP)",
                           lambda: WholeBodyController(backend="daqp-hot")),
                          ("daqp (full QP)",
                           lambda: WholeBodyController(eliminate_dynamics=False)),
                          (PLACO, PlacoController)):
        rows[name] = replay(recording, factory, hold_s=hold_s, timing=timing)
    return {"ticks": len(recording.t), "rows": rows}


# ---------------------------------------------------------------------------- scaling


def _qp_size(controller: BalanceController) -> str:
    if isinstance(controller, PlacoController):
        p = controller.solver.problem
        return (f"{p.n_variables} var ({p.free_variables} free), "
                f"{p.n_inequalities} ineq")
    builder = controller.builder  # type: ignore[attr-defined]
    full, solved = builder.problem, builder.reduced_problem
    if solved is None or not builder.reduced:
        return f"{full.n} var, {full.m} rows + bounds"
    return f"{solved.n} var, {solved.m} rows (reduced from {full.n} var, {full.m} rows)"


def run_scaling(name: str, factory: Callable[[], BalanceController], ticks: int
                ) -> list[dict[str, Any]]:
    """Tick times standing on four feet, then with FR held up (swing task on, then off)."""
    controller = factory()
    loop = _loop(controller)
    sim = loop.sim

    def tick(n: int) -> tuple[list[float], list[float]]:
        times, cpu_times = [], []
        for _ in range(n):
            if lift is not None:
                lift.update(sim.time_s)
            q, v = loop.read_state()
            out, cpu_s = _timed_step(controller, q, v)
            loop.robot.write_command(out)
            times.append(out.timings["total"])
            cpu_times.append(cpu_s)
        return times, cpu_times

    lift = None
    tick(WARMUP_TICKS)
    rows = [("4 contacts, standing", tick(ticks))]
    size4 = _qp_size(controller)
    lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=1e3, timing=SCALING_TIMING)
    lift.start(sim.time_s)
    while lift.phase is not LiftPhase.HOLDING:
        tick(1)
    tick(ticks)  # settle at the hold (untimed)
    rows.append(("3 contacts + swing-foot task (FR held up)", tick(ticks)))
    size3 = _qp_size(controller)
    controller.set_foot_weight(LEG, 0.0)
    rows.append(("3 contacts, swing-foot task weight 0", tick(ticks)))
    sizes = [size4, size3, size3]
    return [{"controller": name, "scenario": label, "qp": size, "ticks": len(times),
             **{f"{k}_us": v for k, v in _stats_us(times).items()},
             "cpu_median_us": _stats_us(cpu_times)["median"]}
            for (label, (times, cpu_times)), size in zip(rows, sizes)]


# ---------------------------------------------------------------------------- reporting


def machine() -> dict[str, Any]:
    """CPU, cores, Python and the versions of the numerical packages."""
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for package in PACKAGES:
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = None
    return {"cpu": cpu, "cores": os.cpu_count(), "python": platform.python_version(),
            "load_average_1_5_15_min": list(os.getloadavg()),
            "platform": platform.platform(), "versions": versions}


def _fmt(value: Any, digits: int = 0) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.{digits}f}" if digits >= 0 else f"{value:.1e}"
    return str(value)


def format_report(report: dict[str, Any]) -> str:
    """The three tables as plain text."""
    m = report["machine"]
    versions = ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v)
    load = m["load_average_1_5_15_min"][0]
    lines = [(f"Machine: {m['cpu']}, {m['cores']} cores, load {load:.2f} at start, "
             f"Python {m['python']}; {versions}"),
             f"Mode: {report['mode']}. {report['episode']['description']}", ""]
    head = (f"{'backend':<22}{'ticks':>6}{'model':>7}{'asm':>7}{'solve':>8}"
            f"{'median':>8}{'p90':>8}{'p99':>8}{'max':>8}{'eq viol':>9}{'ineq viol':>10}"
            f"{'fail':>5}{'x PlaCo':>8}{'cpu med':>8}{'x PlaCo':>8}{'cpu%':>5}")
    lines += ["Tick time [us] per backend (stage columns: medians)", head, "-" * len(head)]
    for row in report["backends"]:
        if row["skipped"]:
            lines.append(f"{row['name']:<22}skipped: {row['skipped']}")
            continue
        st = row["stage_median_us"]
        lines.append(
            f"{row['name']:<22}{row['ticks']:>6}{_fmt(st['model']):>7}"
            f"{_fmt(st['assembly']):>7}{_fmt(st['solve']):>8}{_fmt(row['median_us']):>8}"
            f"{_fmt(row['p90_us']):>8}{_fmt(row['p99_us']):>8}{_fmt(row['max_us']):>8}"
            f"{_fmt(row['max_eq_violation'], -1):>9}{_fmt(row['max_ineq_violation'], -1):>10}"
            f"{row['failures']:>5}{_fmt(row['ratio_to_placo'], 2):>8}"
            f"{_fmt(row['cpu_median_us']):>8}{_fmt(row['cpu_ratio_to_placo'], 2):>8}"
            f"{_fmt(100 * row['cpu_share']):>5}")
    h2h = report["head_to_head"]
    d, p = h2h["default"], h2h["placo"]
    low, mid, high = h2h["block_ratio_p10_p50_p90"]
    lines += ["", (f"Head to head, the same lift in lockstep (turns of {h2h['block_ticks']} "
                   f"ticks): default median {d['median']:.0f} us (p99 {d['p99']:.0f}), PlaCo "
                   f"median {p['median']:.0f} us (p99 {p['p99']:.0f}): ratio of medians "
                   f"{h2h['median_ratio']:.2f}; per turn p10/p50/p90 {low:.2f}/{mid:.2f}/"
                   f"{high:.2f}")]
    rec = report["recorded"]
    lines += ["", (f"Alone, on the recorded states of one lift ({rec['ticks']} ticks, no "
                   "simulation between ticks): tick time [us]")]
    head = f"{'controller':<26}{'model':>7}{'asm':>7}{'solve':>8}{'median':>8}{'p90':>8}{'p99':>8}"
    lines += [head, "-" * len(head)]
    for name, row in rec["rows"].items():
        st = row["stage_median_us"]
        lines.append(f"{name:<26}{_fmt(st.get('model')):>7}{_fmt(st.get('assembly')):>7}"
                     f"{_fmt(st.get('solve')):>8}{_fmt(row['median_us']):>8}"
                     f"{_fmt(row['p90_us']):>8}{_fmt(row['p99_us']):>8}")
    lines += ["", "Scaling: tick time [us] vs contacts and tasks"]
    head = (f"{'controller':<16}{'scenario':<44}{'QP':<36}{'ticks':>6}{'median':>8}{'p90':>8}"
            f"{'p99':>8}{'cpu med':>8}")
    lines += [head, "-" * len(head)]
    for row in report["scaling"]:
        lines.append(f"{row['controller']:<16}{row['scenario']:<44}{row['qp']:<36}"
                     f"{row['ticks']:>6}{_fmt(row['median_us']):>8}{_fmt(row['p90_us']):>8}"
                     f"{_fmt(row['p99_us']):>8}{_fmt(row['cpu_median_us']):>8}")
    ep = report["episode_table"]
    lines += ["", f"Episode quality, {ep['controller']} ({ep['description']})"]
    for key, value in ep["metrics"].items():
        lines.append(f"  {key:<30}{_fmt(value, 3) if isinstance(value, float) else value}")
    lines += ["", *[f"Note: {n}" for n in report["notes"]]]
    return "\n".join(lines)


def plot(report: dict[str, Any], path: Path) -> None:
    """Tick-time distribution per backend (box plot, log scale) and the median stages."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in report["backends"] if not r["skipped"]]
    fig, (left, right) = plt.subplots(1, 2, figsize=(14, 5.5),
                                      gridspec_kw={"width_ratios": [3, 2]})
    left.boxplot([r["total_samples_us"] for r in rows], whis=(1, 99), showfliers=True,
                 flierprops={"markersize": 2, "alpha": 0.3})
    left.set_xticks(range(1, len(rows) + 1), [r["name"] for r in rows], rotation=35,
                    ha="right")
    left.set_yscale("log")
    left.set_ylabel("tick time [us] (whiskers: p1-p99)")
    left.set_title(f"Control tick, closed-loop high five ({report['mode']} mode)")
    left.grid(True, which="both", axis="y", alpha=0.3)
    bottom = np.zeros(len(rows))
    for stage in STAGES[:-1]:
        values = np.array([r["stage_median_us"][stage] or 0.0 for r in rows])
        right.barh(range(len(rows)), values, left=bottom, label=stage)
        bottom += values
    right.set_yticks(range(len(rows)), [r["name"] for r in rows])
    right.set_xlabel("median stage time [us] (stacked; stages a controller reports)")
    right.legend(loc="lower right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


# ---------------------------------------------------------------------------- main


def _controllers() -> list[tuple[str, Callable[[], BalanceController]]]:
    makers: list[tuple[str, Callable[[], BalanceController]]] = [
        (f"{DEFAULT} ({ControllerConfig().backend})", WholeBodyController),
        ("daqp, full QP", lambda: WholeBodyController(eliminate_dynamics=False))]
    for name in available_backends():
        makers.append((name, lambda name=name: WholeBodyController(backend=name)))
    makers.append((PLACO, PlacoController))
    return makers


def run_head_to_head(*, block_ticks: int, hold_s: float, stop_after_s: float | None,
                     timing: LegLiftTiming | None) -> dict[str, Any]:
    """The default controller and PlaCo through the same lift in lockstep.

    Each drives its own simulation; they take turns every ``block_ticks`` ticks. On a shared
    or virtual machine the speed drifts from one episode to the next by more than the two
    controllers differ (medians of single episodes here moved by 2x); in lockstep both see
    the same drift, so the ratio of their medians measures the controllers.
    """
    runs = {}
    for name, factory in ((DEFAULT, WholeBodyController), (PLACO, PlacoController)):
        controller = factory()
        loop = _loop(controller)
        for _ in range(WARMUP_TICKS):
            loop.robot.write_command(controller.step(*loop.read_state()))
        lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s, timing=timing)
        lift.start(loop.sim.time_s)
        runs[name] = (loop, controller, lift, loop.sim.time_s, [])

    def running(run: tuple) -> bool:
        loop, _, lift, start, _ = run
        return lift.phase is not LiftPhase.DONE and (
            stop_after_s is None or loop.sim.time_s - start < stop_after_s - 1e-9)

    while any(running(run) for run in runs.values()):
        for run in runs.values():
            loop, controller, lift, _, samples = run
            for _ in range(block_ticks):
                if not running(run):
                    break
                lift.update(loop.sim.time_s)
                q, v = loop.read_state()
                out, _ = _timed_step(controller, q, v)
                samples.append(out.timings["total"])
                loop.robot.write_command(out)
    default, placo = runs[DEFAULT][4], runs[PLACO][4]
    blocks = min(len(default), len(placo)) // block_ticks
    ratios = [float(np.median(default[i * block_ticks:(i + 1) * block_ticks])
                    / np.median(placo[i * block_ticks:(i + 1) * block_ticks]))
              for i in range(blocks)]
    return {"block_ticks": block_ticks, "default": _stats_us(default),
            "placo": _stats_us(placo),
            "median_ratio": float(np.median(default) / np.median(placo)),
            "block_ratio_p10_p50_p90": [float(np.percentile(ratios, k)) for k in (10, 50, 90)]}


def run(*, quick: bool, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Measure everything; returns the report (see the module docstring)."""
    hold_s = 0.3 if quick else 2.0
    stop = QUICK_LIFT_S if quick else None
    rows: list[dict[str, Any]] = []
    log("  process warm-up (discarded)")
    run_episode(WholeBodyController(), hold_s=hold_s, stop_after_s=0.2)
    for name, factory in _controllers():
        log(f"  episode: {name}")
        try:
            controller = factory()
        except Exception as err:  # noqa: BLE001 - a broken backend becomes a skipped row
            rows.append({"name": name, "skipped": f"{type(err).__name__}: {err}"})
            continue
        with c_stdout_silenced():
            episode = run_episode(controller, hold_s=hold_s, stop_after_s=stop,
                                  timing=QUICK_TIMING if quick else None)
        rows.append(backend_row(name, episode))
    rows += [{"name": name, "skipped": reason} for name, reason in missing_backends().items()]
    placo = next((r for r in rows if r["name"] == PLACO and not r["skipped"]), None)
    for row in rows:
        if not row["skipped"]:
            row["ratio_to_placo"] = row["median_us"] / placo["median_us"] if placo else None
            row["cpu_ratio_to_placo"] = (row["cpu_median_us"] / placo["cpu_median_us"]
                                         if placo else None)

    log("  head to head: default and PlaCo in lockstep")
    head_to_head = run_head_to_head(block_ticks=100, hold_s=hold_s, stop_after_s=stop,
                                    timing=QUICK_TIMING if quick else None)

    log("  alone, on recorded states")
    recorded = run_recorded(hold_s=hold_s, timing=QUICK_TIMING if quick else None)

    log("  episode quality: default backend, whole lift")
    quality = run_episode(WholeBodyController(), hold_s=hold_s, stop_after_s=None, quality=True)
    log("  scaling")
    ticks = 200 if quick else 500
    scaling = run_scaling(DEFAULT, WholeBodyController, ticks)
    scaling += run_scaling(PLACO, PlacoController, ticks)

    lift_desc = (f"{WARMUP_TICKS} standing warm-up ticks (excluded), then LegLift {LEG} to "
                 f"{HEIGHT_M:.2f} m, hold {hold_s:g} s, 1 kHz motor commands in MuJoCo")
    if quick:
        t = QUICK_TIMING
        lift_desc += (f"; timing episodes shift in {t.shift_s:g} s, unload in {t.unload_s:g} s "
                      f"and stop after {QUICK_LIFT_S:g} s of the lift (start of the raise)")
    notes = [
        (f"The first {WARMUP_TICKS} ticks (standing, before the lift) of every episode are "
         "warm-up and excluded from every statistic."),
        ("Stage columns: medians of the stages ControlOutput.timings reports, '-' where a "
         "controller reports none (WholeBodyController may compute its task terms inside "
         "'assembly'; PlaCo's model is update_kinematics, its solve the task update, assembly "
         "and QP together)."),
        ("Violations: WholeBodyController's last_solution checked with problem.violations() "
         "right after each step; PlaCo's are its hard rows (floating-base torque, stance-foot "
         "accelerations, torque limits, unilateral and friction rows), from "
         "PlacoController.solution_violations(); both outside the timed step."),
        "Fallback ticks count in the timing statistics and as failures.",
        ("Wall-clock columns come from ControlOutput.timings; 'cpu med' is the median CPU time "
         "of the calling thread in controller.step (thread_time), which preemption by other "
         "processes does not inflate, and its 'x PlaCo' the ratio of those. cpu%: the "
         "process's CPU time over the episode's wall time; well below 100, other processes "
         "shared the cores and the wall-clock p90-max columns measure their preemptions."),
        ("Before the first row, one short episode of the default controller warms the process "
         "up (imports, caches) and is discarded. Times depend on the machine's load."),
        ("Scaling: a foot in the air has no force variables in either controller's QP; "
         "WholeBodyController then eliminates the dynamics and the stance contacts, so the "
         "solver sees 13 variables on three or four feet. A swing task at weight 0 "
         "(set_foot_weight) stays registered; at weight 0 the foot droops under the posture "
         "task."),
        ("Episode quality: sim.episode_metrics (MuJoCo-measured; stance feet are the fully "
         "loaded ones, the CoM margin is over the feet MuJoCo sees loaded), raised-foot error "
         "against the controller's foot target. Real-time factor: the lift's sim time over "
         "the wall time of lift update + controller + physics (metric queries excluded)."),
    ]
    return {
        "machine": machine(),
        "mode": "quick" if quick else "full",
        "episode": {"leg": LEG, "height_m": HEIGHT_M, "hold_s": hold_s,
                    "warmup_ticks_excluded": WARMUP_TICKS,
                    "stop_after_lift_s": stop, "description": lift_desc},
        "backends": rows,
        "head_to_head": head_to_head,
        "recorded": recorded,
        "scaling": scaling,
        "episode_table": {"controller": f"{DEFAULT} backend",
                          "description": f"whole lift, hold {hold_s:g} s",
                          "sim_s": quality.sim_s,
                          "metrics": quality.metrics},
        "notes": notes,
    }


def _json_safe(value: Any) -> Any:
    """Non-finite numbers become ``null`` (JSON has no NaN or infinity)."""
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, np.integer | np.bool_):
        return value.item()
    return value


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.qp_timing",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"stop each timing episode after {QUICK_LIFT_S:g} s of the lift")
    parser.add_argument("--json", type=Path, default=Path("out/qp_timing.json"),
                        help="where to write the report (default: out/qp_timing.json)")
    parser.add_argument("--plot", type=Path, default=Path("out/qp_timing.png"),
                        help="where to write the plot (default: out/qp_timing.png)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    with warnings.catch_warnings():
        # Notices third-party solvers repeat every tick (qpsolvers converting dense matrices
        # for OSQP, osqp's raise_error default); the conversion's cost stays in the timing.
        warnings.filterwarnings("ignore", message="Converted matrix")
        warnings.simplefilter("ignore", PendingDeprecationWarning)
        report = run(quick=args.quick, log=lambda msg: print(
            f"[{time.perf_counter() - started:6.1f} s] {msg}", file=sys.stderr, flush=True))
    report["benchmark_wall_s"] = time.perf_counter() - started
    print(format_report(report))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(_json_safe(report), indent=1, allow_nan=False))
    plot(report, args.plot)
    print(f"\nWrote {args.json} and {args.plot} in {report['benchmark_wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
