"""Per-tick QP timing of every backend and of PlaCo on a closed-loop high five in MuJoCo.

Run ``python -m benchmarks.qp_timing [--quick] [--json PATH] [--plot PATH]``.

Four tables (the runs: :mod:`benchmarks.lift_timing`), all measured through the library's
public API, every controller reading the
state estimated from the default plant's simulated sensors (the loop's default estimator),
every quality figure measured on the simulator's truth:

1. Backends: one closed-loop episode per backend (200 standing warm-up ticks, excluded from
   the statistics, then a ``LegLift`` of leg FR to 0.40 m at 1 kHz, motor commands to the
   default Menagerie plant). Each tick's ``ControlOutput.timings`` give the stage times; the
   returned QP solution is checked against the problem it solved. The full mode runs the
   whole lift with a 2 s hold; ``--quick`` shifts in 0.5 s, unloads in 0.3 s and stops after
   1.0 s of the lift (the first 0.2 s of the raise), so that the one-shot OSQP (~4 ms a tick)
   stays short.
2. Alone, on recorded states: one closed-loop lift's estimated states replayed into fresh
   controllers (the default; DAQP with its hot start; the full QP without the elimination;
   PlaCo), with no simulation between ticks: the controller's own time, caches warm.
3. Scaling: tick time against the number of contacts (four feet standing; three with the
   foot held up) and with the swing-foot task's weight set to zero, for the default
   backend and PlaCo (reaching the hold with faster phases: only the hold is timed), the
   two in turns of 50 ticks on each scenario, like the lockstep.
4. Episode quality of the default backend over a whole lift (hold 2 s, or 0.3 s in quick
   mode): tracking, slip, forces, margins, torques, failures, real-time factor.
"""

from __future__ import annotations

import argparse
import contextlib
import ctypes
import json
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.lift_timing import (
    DEFAULT,
    HEIGHT_M,
    HOLD_S,
    LEG,
    PLACO,
    QUICK_HOLD_S,
    QUICK_LIFT_S,
    QUICK_TIMING,
    STAGES,
    WARMUP_TICKS,
    TimedLift,
    run_episode,
    run_head_to_head,
    run_recorded,
    run_scaling,
    stats_us,
)
from benchmarks.qp_timing_report import format_report, plot
from benchmarks.reporting import json_safe, machine
from benchmarks.tsid_row import run_tsid_row
from wbc.backends.backend import available_backends, missing_backends
from wbc.controller.balance_controller import BalanceController
from wbc.controller.controller_config import ControllerConfig
from wbc.controller.placo_controller import PlacoController
from wbc.controller.whole_body_controller import WholeBodyController


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


# ---------------------------------------------------------------------------- measuring


def backend_row(name: str, episode: TimedLift) -> dict[str, Any]:
    """One row of the backend table from an episode."""
    violations = np.array(episode.violations) if episode.violations else np.full((1, 2), np.nan)
    total = stats_us(episode.timings["total"])
    stages = {s: stats_us(episode.timings[s])["median"] for s in STAGES[:-1]}
    return {
        "name": name, "skipped": None, "ticks": episode.ticks, "sim_s": episode.sim_s,
        **{f"{k}_us": v for k, v in total.items()},
        "stage_median_us": stages,
        "cpu_median_us": stats_us(episode.cpu_times)["median"],
        "max_eq_violation": _finite_or_none(np.nanmax(violations[:, 0])),
        "max_ineq_violation": _finite_or_none(np.nanmax(violations[:, 1])),
        "failures": episode.failures,
        "cpu_share": episode.cpu_share,
        "total_samples_us": [round(1e6 * t, 2) for t in episode.timings["total"]],
    }


def _finite_or_none(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


# ---------------------------------------------------------------------------- main


def _controllers() -> list[tuple[str, Callable[[], BalanceController]]]:
    makers: list[tuple[str, Callable[[], BalanceController]]] = [
        (f"{DEFAULT} ({ControllerConfig().solver.backend})", WholeBodyController),
        ("daqp, full QP", lambda: WholeBodyController(solver={"eliminate_dynamics": False}))]
    for name in available_backends():
        makers.append((name, lambda name=name: WholeBodyController(solver={"backend": name})))
    makers.append((PLACO, PlacoController))
    return makers


def run(*, quick: bool, log: Callable[[str], None] = print) -> dict[str, Any]:
    """Measure everything; returns the report (see the module docstring)."""
    hold_s = QUICK_HOLD_S if quick else HOLD_S
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
    scaling = run_scaling(ticks, block_ticks=50,
                          controllers=((DEFAULT, WholeBodyController), (PLACO, PlacoController)))
    log("  TSID, if an environment has it (make tsid)")
    tsid = run_tsid_row(hold_s=hold_s, timing=QUICK_TIMING if quick else None)

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
         "task. The two controllers take turns of 50 ticks on each scenario (each reached "
         "by both first, untimed); 'x PlaCo' is the ratio of medians, 'turns' the p10/p50/p90 "
         "of the per-turn ratios of medians."),
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
        "tsid": tsid,
        "episode_table": {"controller": f"{DEFAULT} backend",
                          "description": f"whole lift, hold {hold_s:g} s",
                          "sim_s": quality.sim_s,
                          "metrics": quality.metrics},
        "notes": notes,
    }


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
    args.json.write_text(json.dumps(json_safe(report), indent=1, allow_nan=False))
    plot(report, args.plot)
    print(f"\nWrote {args.json} and {args.plot} in {report['benchmark_wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
