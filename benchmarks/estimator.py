"""The state estimators' accuracy and cost, beside the controller on the truth, in one run.

Run ``python -m benchmarks.estimator [--quick] [--json PATH]``.

Every episode is closed loop on the default plant and the ``go2`` sensors: the controller
reads each estimator's state (or, in the ``truth`` rows, the simulator's exact state), and
everything is measured on the simulator's true state:

1. The high five (0.40 m, hold 2 s) at 1 kHz and at 500 Hz.
2. Pushes on the base during a 1 s hold: 3 N s in 8 directions and 8 N s toward the raised
   foot's corner (315 deg) and away from it (135 deg); each row is the worst of them.
3. Standing 60 s.

Columns: the goal's outcome, the raised foot's tracking (RMS over the motion and while
holding [mm]), and the estimate against the truth: base linear velocity error (RMS and max
[mm/s]), height error (max [mm]) and its drift, roll and pitch error (max [deg]), horizontal
drift (at the end and max [mm]) and yaw drift (at the end [deg]) since the goal began.

Last, each estimator's cost: its ``update`` alone on the sensor records of a recorded high
five (median and p99 [us], best of three passes), and its time inside the loop (the
``estimator`` part of ``benchmarks.loop_timing``'s breakdown). ``--quick`` runs the 1 kHz
high five, one push and 10 s of standing.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.reporting import machine, run_and_report
from benchmarks.robustness import PlantCase, hold_push, run_high_five
from sim.control_loop import ControlLoop
from sim.episode import episode_default
from sim.episode_runner import EpisodeRunner
from wbc.controller.control_output import ControlOutput
from wbc.estimation.estimators import ESTIMATORS, make_estimator
from wbc.robot_io.sensor_record import SensorRecord

#: The high five of the first rows and of the recorded records: the default episode's.
GOAL = episode_default("goal")
#: The state sources compared: the simulator's truth, then each estimator by name.
SOURCES = ("truth", *ESTIMATORS)
#: Pushes of the push rows: (direction [deg], impulse [N s]).
PUSHES = tuple((d, 3.0) for d in range(0, 360, 45)) + ((315, 8.0), (135, 8.0))
QUICK_PUSHES = ((90, 3.0),)
STANDING_S, QUICK_STANDING_S = 60.0, 10.0
#: Summary fields of the tables (from :class:`sim.episode_metrics.EpisodeSummary`).
FIELDS = ("raised_foot_rms_mm", "holding_rms_mm", "estimate_velocity_rms_m_s",
          "estimate_velocity_max_m_s", "estimate_height_max_mm", "estimate_height_drift_mm",
          "estimate_roll_max_deg", "estimate_pitch_max_deg", "estimate_horizontal_drift_mm",
          "estimate_horizontal_drift_max_mm", "estimate_yaw_drift_deg")


def case(source: str, control_period_s: float = 1e-3) -> PlantCase:
    """The default plant and sensors with the controller on ``source``'s state."""
    if source == "truth":
        return PlantCase(source, state="truth", control_period_s=control_period_s)
    return PlantCase(source, estimator=source, control_period_s=control_period_s)


def _row(source: str, scenario: str, status: str, summary: Any) -> dict[str, Any]:
    row = {"source": source, "scenario": scenario, "status": status}
    row.update({name: round(float(getattr(summary, name)), 5) for name in FIELDS})
    return row


def high_five_row(source: str, control_period_s: float) -> dict[str, Any]:
    """The high five (0.40 m, hold 2 s) at a control period, measured."""
    episode = run_high_five(case(source, control_period_s), hold_s=GOAL.hold_seconds,
                            height_m=GOAL.target_height)
    return _row(source, f"high five, {1.0 / control_period_s:g} Hz", episode.status.name,
                episode.summary)


def push_row(source: str, pushes: Sequence[tuple[float, float]]) -> dict[str, Any]:
    """The worst of the pushes' episodes (1 s hold), field by field; its outcomes."""
    rows = []
    for direction, impulse in pushes:
        episode = run_high_five(case(source), pushes=[hold_push(direction, impulse)])
        rows.append(_row(source, "", episode.status.name, episode.summary))
    worst = {"source": source, "scenario": f"pushes ({len(pushes)})",
             "status": "/".join(sorted({r["status"] for r in rows}))}
    for name in FIELDS:
        values = [r[name] for r in rows]
        worst[name] = max(values, key=abs)
    worst["outcomes"] = [f"{d:g} deg {i:g} N s: {r['status']}"
                         for (d, i), r in zip(pushes, rows)]
    return worst


def standing_row(source: str, seconds: float) -> dict[str, Any]:
    """Standing ``seconds`` [s] after the settle: the estimate's drift."""
    episode = case(source).episode(height_m=GOAL.target_height, hold_s=GOAL.hold_seconds)
    episode = episode.replace(action=None, after_s=seconds)
    result = EpisodeRunner(episode, metrics=True).run()
    status = "STANDING" if result.loop.controller.failures == 0 else "FAULTS"
    return _row(source, f"standing {seconds:g} s", status, result.metrics)


class _Records:
    """Every sensor record the estimator read, with the contact schedule it was given (a
    loop hook)."""

    def __init__(self) -> None:
        self.records: list[tuple[SensorRecord, np.ndarray]] = []

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        sample = loop.estimator.last_sample
        if sample is not None:
            self.records.append((sample.copy(), loop.estimator.last_schedule))


def recorded_records() -> list[tuple[SensorRecord, np.ndarray]]:
    """The sensor records and contact schedules of a high five (0.40 m, hold 2 s; the
    controller on the default estimator), in the description's orders."""
    recording = _Records()
    episode = case(next(iter(ESTIMATORS))).episode(height_m=GOAL.target_height,
                                                   hold_s=GOAL.hold_seconds)
    EpisodeRunner(episode, hooks=[recording]).run()
    return recording.records


def cost_row(name: str, records: list[tuple[SensorRecord, np.ndarray]]) -> dict[str, Any]:
    """``update`` alone over the recorded records: best of three passes' median and p99.

    Each record is copied (untimed) into one buffer, as a robot refills its own record each
    tick, which the estimator's one compiled call is bound to.
    """
    passes = []
    for _ in range(3):
        estimator = make_estimator(name)
        buffer = records[0][0].copy()
        estimator.reset(buffer)
        times = np.empty(len(records) - 1)
        clock = time.perf_counter
        for k, (sample, schedule) in enumerate(records[1:]):
            buffer.copy_from(sample)
            start = clock()
            estimator.update(buffer, schedule)
            times[k] = clock() - start
        passes.append((float(np.median(times)) * 1e6, float(np.percentile(times, 99)) * 1e6))
    median, p99 = min(passes)
    return {"estimator": name, "what": ESTIMATORS[name], "updates": len(records) - 1,
            "median_us": round(median, 2), "p99_us": round(p99, 2)}


def run(*, quick: bool = False, log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Every table; the report as a dict."""
    rows = []
    periods = (1e-3,) if quick else (1e-3, 2e-3)
    for period in periods:
        for source in SOURCES:
            log(f"high five at {1.0 / period:g} Hz on {source}")
            rows.append(high_five_row(source, period))
    for source in SOURCES:
        log(f"pushes on {source}")
        rows.append(push_row(source, QUICK_PUSHES if quick else PUSHES))
    for source in SOURCES:
        log(f"standing on {source}")
        rows.append(standing_row(source, QUICK_STANDING_S if quick else STANDING_S))
    log("each estimator's update on recorded sensor records")
    records = recorded_records()
    costs = [cost_row(name, records) for name in ESTIMATORS]
    return {"machine": machine(), "mode": "quick" if quick else "full", "rows": rows,
            "cost": costs}


def format_report(report: dict[str, Any]) -> str:
    """The report as plain text tables."""
    m = report["machine"]
    header = f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}"
    lines = [f"{header}; mode {report['mode']}", ""]
    head = (f"{'scenario':<20}{'state':<7}{'status':>20}{'track':>7}{'hold':>6}{'v RMS':>7}"
            f"{'v max':>7}{'h max':>7}{'h drift':>8}{'roll':>6}{'pitch':>6}{'drift':>7}"
            f"{'max':>6}{'yaw':>7}")
    units = (f"{'':<20}{'':<7}{'':>20}{'[mm]':>7}{'[mm]':>6}{'[mm/s]':>7}{'[mm/s]':>7}"
             f"{'[mm]':>7}{'[mm]':>8}{'[deg]':>6}{'[deg]':>6}{'[mm]':>7}{'[mm]':>6}"
             f"{'[deg]':>7}")
    lines += [head, units, "-" * len(head)]
    for r in report["rows"]:
        lines.append(
            f"{r['scenario']:<20}{r['source']:<7}{r['status']:>20}"
            f"{r['raised_foot_rms_mm']:>7.2f}{r['holding_rms_mm']:>6.2f}"
            f"{r['estimate_velocity_rms_m_s'] * 1e3:>7.1f}"
            f"{r['estimate_velocity_max_m_s'] * 1e3:>7.1f}{r['estimate_height_max_mm']:>7.2f}"
            f"{r['estimate_height_drift_mm']:>8.2f}{r['estimate_roll_max_deg']:>6.2f}"
            f"{r['estimate_pitch_max_deg']:>6.2f}{r['estimate_horizontal_drift_mm']:>7.1f}"
            f"{r['estimate_horizontal_drift_max_mm']:>6.1f}{r['estimate_yaw_drift_deg']:>7.2f}")
    lines += ["", "Cost of update() alone on a recorded high five's sensor records:"]
    for c in report["cost"]:
        lines.append(f"  {c['estimator']:<6} ({c['what']}): median {c['median_us']:.1f} us, "
                     f"p99 {c['p99_us']:.1f} us over {c['updates']} updates")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.estimator",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="the 1 kHz high five, one push and 10 s of standing")
    parser.add_argument("--json", type=Path, default=Path("out/estimator.json"),
                        help="where to write the report (default: out/estimator.json)")
    args = parser.parse_args(argv)
    return run_and_report(lambda log: run(quick=args.quick, log=log),
                          format_report, args.json)


if __name__ == "__main__":
    raise SystemExit(main())
