"""The controller on the wall clock across processes: ``go2-wbc bridge``, ``go2-wbc run --dds``
and ``go2-wbc high-five --dds`` clients on a private DDS domain on loopback, N high fives, at
500 Hz and 1 kHz.

Run ``python -m benchmarks.realtime_loop [--rate 500|1000|both] [--goals N] [--ordinary]
[--load N] [--json [PATH]]``.

For each rate: the bridge (LowState_ at the rate), the controller (at the rate), then N high
fives (0.4 m, held 2 s) one after the other, each from a new client process; then Ctrl-C to
the controller (cancel, sit, damp, exit) and to the bridge. The table comes from their
reports and logs (:mod:`benchmarks.dds_outputs`, :func:`sim.dds_evaluation.goal_runs`):

- ticks and deadline misses: the controller's whole run (its start-up stand, the goals, the
  clients' start-ups, the sit at the end), and during the high fives alone (its tick log);
- state -> command latency at the bridge, from writing a LowState_: "received" is to the
  arrival of the command answering it (the issue's latency: the bridge waits on its command
  reader between physics steps); "taken" is to the physics step that applies it (it adds the
  wait for that 1 ms step); "written" is to the controller's write of the command (its DDS
  source timestamp, the same host's clock);
- commands: sent by the controller, received by the bridge (a newer one that arrives before
  the bridge's next 1 ms step replaces the older in its reader: the difference), states no
  command answered ("replies lost");
- rejected frames and CRC errors both ways; physics overruns (the bridge fell behind the
  clock);
- the controller's tick by stage (wall time of each stage, mean and p99; "cpu" is the loop
  thread's CPU time of the whole tick), and each process's CPU share over its life;
- quality: each goal's figures against the simulator's truth, mean and worst over the goals.

Both loops run real-time (``SCHED_FIFO`` while they run, the processes' default when the
machine permits it; :mod:`actions.robot.realtime_priority`); ``--ordinary`` runs them under
ordinary scheduling instead, and ``--load N`` runs N CPU-bound ordinary processes beside them
(a busy machine). The notes say which scheduling each loop ran under.

The machine's load average is printed at the start and the end of each rate's run: three
Python processes share the cores with whatever else runs, and a client's start-up (about a
CPU second of imports) competes with the loop on a 2-core machine.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.dds_outputs import (
    BridgeFigures,
    ControllerFigures,
    client_outcome,
    loop_scheduling,
)
from benchmarks.dds_processes import DdsProcesses, private_domain_id
from benchmarks.reporting import json_safe, machine
from sim.dds_evaluation import goal_runs

#: The high five of every goal.
HEIGHT_M, HOLD_S = 0.4, 2.0
#: Longest wait for one goal [s].
GOAL_TIMEOUT_S = 60.0
#: Quality figures reported (attribute of GoalRunMetrics or estimate key, label, scale).
QUALITY = (("raised_foot_rms_mm", "raised foot RMS [mm]", 1.0),
           ("raised_foot_max_mm", "raised foot max [mm]", 1.0),
           ("holding_rms_mm", "holding RMS [mm]", 1.0),
           ("stance_travel_max_mm", "stance foot travel max [mm]", 1.0),
           ("max_tilt_deg", "base tilt max [deg]", 1.0),
           ("velocity_rms_m_s", "estimate: velocity RMS [mm/s]", 1e3),
           ("height_max_mm", "estimate: height error max [mm]", 1.0),
           ("roll_max_deg", "estimate: roll error max [deg]", 1.0),
           ("pitch_max_deg", "estimate: pitch error max [deg]", 1.0))


def run_rate(rate_hz: int, goals: int, workdir: Path, *, domain_id: int,
             ordinary: bool = False, load: int = 0) -> dict[str, Any]:
    """Bridge, controller and ``goals`` high-five clients at ``rate_hz`` (loops under
    ordinary scheduling with ``ordinary``; ``load`` CPU-bound processes beside them); their
    figures."""
    with busy_processes(load):
        return _run_rate(rate_hz, goals, workdir, domain_id=domain_id,
                         scheduling=["--rt-priority", "0"] if ordinary else [], load=load)


@contextlib.contextmanager
def busy_processes(count: int) -> Iterator[None]:
    """``count`` CPU-bound Python processes under ordinary scheduling while the block runs."""
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"])
            for _ in range(count)]
    try:
        yield
    finally:
        for process in busy:
            process.kill()
            process.wait()


def _run_rate(rate_hz: int, goals: int, workdir: Path, *, domain_id: int,
              scheduling: list[str], load: int) -> dict[str, Any]:
    load_start = os.getloadavg()
    wall_start = time.monotonic()
    outcomes = []
    with DdsProcesses(workdir, domain_id=domain_id) as run:
        bridge = run.bridge(*scheduling, rate_hz=rate_hz)
        controller = run.controller(*scheduling, rate_hz=rate_hz)
        for _ in range(goals):
            started = time.monotonic()
            client = run.high_five(height_m=HEIGHT_M, hold_s=HOLD_S)
            code = client.wait(GOAL_TIMEOUT_S)
            outcome = client_outcome(client.output())
            outcomes.append({"exit": code, "status": outcome.status,
                             "message": outcome.message,
                             "wall_s": time.monotonic() - started})
        controller_cpu = _cpu_share(controller.cpu_s(), controller.started_s)
        controller.stop()
        bridge.stop()
    wire = BridgeFigures.read(bridge.report_path)
    loop = ControllerFigures.read(controller.report_path)
    runs = [r for r in goal_runs(controller.log_path, bridge.log_path) if r.action == "high_five"]
    goal_misses, goal_ticks = high_five_misses(controller.log_path)
    return {
        "rate_hz": rate_hz, "goals": outcomes, "wall_s": time.monotonic() - wall_start,
        "scheduling": {"bridge": loop_scheduling(bridge.output()),
                       "controller": loop_scheduling(controller.output())},
        "background_load": load,
        "load_average_start": list(load_start), "load_average_end": list(os.getloadavg()),
        "controller": {"ticks": loop.ticks, "deadline_misses": loop.deadline_misses,
                       "miss_percent": loop.miss_percent, "goal_ticks": goal_ticks,
                       "goal_deadline_misses": goal_misses,
                       "no_fresh_state_ticks": loop.no_fresh_state_ticks,
                       "watchdog_trips": loop.watchdog_trips, "robot": loop.robot,
                       "series": loop.series, "cpu_percent": controller_cpu,
                       "gc": loop.raw.get("gc")},
        "bridge": {"states_published": wire.states_published,
                   "publish_rate_hz": wire.publish_rate_hz,
                   "commands_received": wire.commands_received,
                   "commands_applied": wire.commands_applied,
                   "commands_rejected": wire.commands_rejected,
                   "replies_lost": wire.replies_lost, "overruns": wire.overruns,
                   "received_ms": wire.received_ms, "taken_ms": wire.taken_ms,
                   "written_ms": wire.written_ms,
                   "cpu_percent": wire.cpu_percent, "gc": wire.raw.get("gc")},
        "quality": [r.as_dict() for r in runs],
    }


def high_five_misses(log_path: Path) -> tuple[int, int]:
    """Deadline misses and ticks while a high five ran, from a controller's tick log."""
    with np.load(log_path) as ticks:
        names = [str(name) for name in ticks["action_names"]]
        during = ticks["goal_action"] == names.index("high_five")
        return int(ticks["missed"][during].sum()), int(during.sum())


def _cpu_share(cpu_s: float | None, started_s: float) -> float | None:
    """CPU time over wall time since the start [% of one core]."""
    elapsed = time.monotonic() - started_s
    return None if cpu_s is None or elapsed <= 0 else 100.0 * cpu_s / elapsed


def _ms(figures: dict[str, Any]) -> str:
    return " ".join(f"{key} {figures[key]:.2f}" if figures.get(key) is not None
                    else f"{key} -" for key in ("median", "p99", "max"))


def table(result: dict[str, Any]) -> list[str]:
    """The printed table of one rate's run, with its notes."""
    ctrl, wire = result["controller"], result["bridge"]
    robot, series = ctrl["robot"], ctrl["series"]
    statuses = [g["status"] or f"exit {g['exit']}" for g in result["goals"]]
    rejected = sum(wire["commands_rejected"].values())
    sent = robot.get("commands_sent", 0)

    def row(label: str, value: str) -> str:
        return f"  {label:<46} {value}"

    header = (f"realtime loop at {result['rate_hz']} Hz: {len(statuses)} high fives "
              f"({HEIGHT_M:g} m, held {HOLD_S:g} s): {', '.join(statuses)}; "
              f"{result['wall_s']:.1f} s wall")
    lines = [header,
             row("controller ticks", f"{ctrl['ticks']} ({ctrl['goal_ticks']} during high fives)"),
             row("deadline misses",
                 f"{ctrl['deadline_misses']} ({ctrl['miss_percent']:.2f} %); during high fives "
                 f"{ctrl['goal_deadline_misses']} "
                 f"({100.0 * ctrl['goal_deadline_misses'] / max(ctrl['goal_ticks'], 1):.2f} %)"),
             row("ticks without a fresh state / watchdog",
                 f"{ctrl['no_fresh_state_ticks']} / {ctrl['watchdog_trips']} trips"),
             row("latency state -> command received [ms]", _ms(wire["received_ms"])),
             row("latency state -> command taken [ms]", _ms(wire["taken_ms"])),
             row("latency state -> command written [ms]", _ms(wire["written_ms"])),
             row("commands sent / received / not received",
                 f"{sent} / {wire['commands_received']} / {sent - wire['commands_received']}"),
             row("states published / not answered",
                 f"{wire['states_published']} ({wire['publish_rate_hz']:.1f} Hz) / "
                 f"{wire['replies_lost']}"),
             row("rejected commands (CRC) / bad states",
                 f"{rejected} ({wire['commands_rejected'].get('crc', 0)}) / "
                 f"{robot.get('bad_frames', 0)}"),
             row("bridge physics overruns", str(wire["overruns"]))]
    for name in ("read", "actions", "controller", "write", "bridge", "hooks", "gc", "tick",
                 "cpu"):
        label = "tick: thread CPU [ms] mean / p99" if name == "cpu" else \
            f"tick: {name} [ms] mean / p99"
        lines.append(row(label, f"{series[name]['mean_ms']:.3f} / {series[name]['p99_ms']:.3f}"))
    for who, figures in (("controller", ctrl["gc"]), ("bridge", wire["gc"])):
        if figures:
            lines.append(row(f"garbage collections, {who}: by generation / longest [ms]",
                             "{} / {} ({} postponed, {} forced)".format(
                                 "+".join(map(str, figures["collections"])),
                                 "+".join(f"{x:.2f}" for x in figures["longest_ms"]),
                                 figures["postponed"], figures["forced"])))
    cpu = ctrl["cpu_percent"]
    lines.append(row("CPU [% of a core]: controller / bridge",
                     f"{'-' if cpu is None else f'{cpu:.0f}'} / {wire['cpu_percent']:.0f}"))
    quality = result["quality"]
    for key, label, scale in QUALITY:
        values = [scale * (q[key] if key in q else q["estimate"][key]) for q in quality]
        if values:
            lines.append(row(f"{label} mean / worst",
                             f"{np.mean(values):.2f} / {np.max(values):.2f}"))
    if quality:
        lines.append(row("on four feet at the end",
                         f"{sum(q['on_four_feet'] for q in quality)} of {len(quality)}"))
    start, end = result["load_average_start"], result["load_average_end"]
    loads = ", ".join(f"{x:.2f}" for x in start), ", ".join(f"{x:.2f}" for x in end)
    lines += [
        (f"  notes: load average (1, 5, 15 min) {loads[0]} at the start, {loads[1]} at the "
         f"end, on {os.cpu_count()} cores, with {result['background_load']} CPU-bound "
         "processes beside the three."),
        f"  Bridge's loop: {result['scheduling']['bridge']}.",
        f"  Controller's loop: {result['scheduling']['controller']}.",
        ("  Misses over the whole run include each client's start-up (about a CPU second of "
         "imports sharing the cores);"),
        ("  'received' is the command's arrival at the bridge; 'taken' adds the wait for its "
         "next 1 ms physics step; 'written' is on the host's clock (same host only)."),
        ("  Stage times are wall time (a descheduled thread counts); 'thread CPU' is the loop "
         "thread's CPU time per tick.")]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rate", choices=("500", "1000", "both"), default="both",
                        help="control rate [Hz] (default: both)")
    parser.add_argument("--goals", type=int, default=3, metavar="N",
                        help="high fives per rate (default: 3)")
    parser.add_argument("--json", nargs="?", const="-", metavar="PATH",
                        help="print the figures as JSON instead of the table ('--json'), or "
                             "also write them to PATH")
    parser.add_argument("--keep", type=Path, metavar="DIR",
                        help="keep the processes' outputs, reports and logs in DIR (default: "
                             "a temporary directory, removed)")
    parser.add_argument("--ordinary", action="store_true",
                        help="run both loops under ordinary scheduling (default: real-time "
                             "when permitted)")
    parser.add_argument("--load", type=int, default=0, metavar="N",
                        help="CPU-bound ordinary processes running beside the three (default: "
                             "0)")
    args = parser.parse_args(argv)
    if args.load < 0:
        parser.error(f"--load: expected a whole number >= 0, received {args.load}")
    if args.goals < 1:
        parser.error(f"--goals: expected a whole number >= 1, received {args.goals}")
    rates = (500, 1000) if args.rate == "both" else (int(args.rate),)
    results = []
    with tempfile.TemporaryDirectory(prefix="realtime_loop_") as scratch:
        root = args.keep or Path(scratch)
        for k, rate in enumerate(rates):
            result = run_rate(rate, args.goals, root / f"{rate}hz",
                              domain_id=private_domain_id(2 + k), ordinary=args.ordinary,
                              load=args.load)
            results.append(result)
            if args.json != "-":
                print("\n".join(table(result)) + "\n", flush=True)
    report = json_safe({"machine": machine(), "runs": results})
    if args.json == "-":
        json.dump(report, sys.stdout, indent=2)
        print()
    elif args.json:
        Path(args.json).write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    failed = [g for r in results for g in r["goals"] if g["status"] != "SUCCEEDED"]
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
