"""Whole-loop timing of ``go2-wbc high-five``: real-time factor and a per-tick breakdown.

Run ``python -m benchmarks.loop_timing [--quick] [--json PATH]``.

The episode is the default :class:`sim.episode.Episode`, which is ``go2-wbc high-five``'s
(its height and hold, the default plant and sensors, the controller on the estimated state,
the robot standing its ``settle_s`` before the goal), run by
:class:`sim.episode_runner.EpisodeRunner` as the command line runs it, at 1 kHz and at 500
Hz (``control_period_s=2e-3``, two 1 ms physics steps per tick), and the same on the
simulator's exact state (``--state truth``) for comparison: the estimate's cost is the ratio
of the two real-time factors. Each rate and state gets two episodes on fresh loops, both
timed from the goal's sending to its result, as the command line times a run:

1. Per-tick breakdown: the runner ticks with :class:`benchmarks.timed_ticks.TimedTicks`, which
   runs the loop's own tick (``spin_once``'s) with a timer that marks each stage's end (the
   parts below).
2. Real-time factor: ``ControlLoop.spin_once`` until the result, as the command line drives
   it; sim time over wall time, and the process's CPU time over that wall time (well below
   1: other processes took the cores). It runs second, so that it measures the loop rather
   than the one-off costs of the process's first goal (a fresh ``go2-wbc`` pays those:
   about 10 % more wall time at 1 kHz).

The parts of a tick:

- ``sensors``: ``robot.read_sensors()`` (the simulated sensors, their noise, the joint and
  leg orders); with ``--state truth``, ``robot.read_state()`` (MuJoCo to Pinocchio);
- ``estimator``: ``loop.estimate_state`` (the contact schedule, the state estimator's tick,
  the copies of ``q`` and ``v``; nothing with ``--state truth``) and ``context.observe``;
- ``actions``: the action runner's tick (the action servers and the behaviours: the high
  five's phases and balance watch);
- ``controller``: ``controller.step``, and below it the stages its
  ``ControlOutput.timings`` report (whatever their names);
- ``physics``: ``robot.write_command`` (the command's checks and joint order, the motor
  drivers, MuJoCo's step or steps), and below it ``mj_step`` alone (``mujoco.mj_step``
  wrapped in a timer for this episode);
- ``rest``: ``loop.guard`` (the command checks before sending), the bookkeeping of the
  output and the loop's hooks (none by default; ``--metrics``' hook in the third run);
- ``tick``: all of it, and ``around controller``: the tick less ``controller.step``.

Last, a fresh interpreter builds the loop and times, tick by tick, its first ticks standing
and one goal of each action (:func:`fresh_process_ticks`): their worst ticks show any
one-off work (compiled code loaded, a QP layout built) that lands inside a control period.

Full mode also runs the 1 kHz episode with the hook ``go2-wbc --metrics`` adds. ``--quick``
holds the foot 0 s instead of the command line's default and skips that run.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from actions.go2.go2_interfaces import HighFiveGoal, SitGoal, StandGoal
from actions.ros_interfaces.control_msgs import FollowJointTrajectoryGoal
from actions.ros_interfaces.trajectory_msgs import JointTrajectory, JointTrajectoryPoint
from benchmarks.reporting import machine, run_and_report
from benchmarks.timed_ticks import TimedTicks
from sim.episode import Episode, episode_default
from sim.episode_loop import build_loop, startup_objects_frozen
from sim.episode_result import NO_GOAL
from sim.episode_runner import EpisodeRunner

#: Control periods [s] of the runs: 1 kHz and the GO2's usual 500 Hz.
PERIODS_S = (1e-3, 2e-3)
#: Where the controller's state comes from in the runs, and the runs' order at each rate.
STATES = ("estimate", "truth")
#: The hold [s] of a quick run.
QUICK_HOLD_S = 0
#: The packages whose versions the report lists.
PACKAGES = ("mujoco", "numpy", "numba", "pin", "daqp")


def episode_defaults() -> dict[str, Any]:
    """The default episode's goal, plant and rates (``go2-wbc high-five``'s, with no options)."""
    goal = episode_default("goal")
    return {"target_height": goal.target_height, "hold_seconds": goal.hold_seconds,
            "plant": Episode().plant_model,
            "control_rate_hz": 1.0 / episode_default("control_period_s"),
            "settle_s": episode_default("settle_s")}


def _run(period_s: float, goal: HighFiveGoal, state: str, metrics: bool, *,
         instrumented: bool = False) -> tuple[dict[str, Any], TimedTicks | None]:
    """One high five from its sending to its result on a fresh loop: sim time, wall time,
    CPU share; ``instrumented``: its ticks run as :class:`TimedTicks`, which come back."""
    runner = EpisodeRunner(Episode(goal=goal, control_period_s=period_s, state=state),
                           metrics=metrics)
    timed = None
    if instrumented:
        timed = TimedTicks(runner.loop)
        with timed.timing_mj_step():
            result = runner.run(tick=timed)
    else:
        result = runner.run()
    return {"status": result.status, "ticks": result.ticks, "sim_s": result.sim_s,
            "wall_s": result.wall_s, "real_time_factor": result.sim_s / result.wall_s,
            "cpu_share": result.cpu_s / result.wall_s,
            "feedback_messages": len(result.feedback)}, timed


def run_rate(period_s: float, goal: HighFiveGoal, *, metrics: bool = False,
             state: str = "estimate") -> dict[str, Any]:
    """The two episodes at one control period: the breakdown, then the real-time factor."""
    # The instrumented episode first: the process's first goal also pays one-off costs
    # (compiled code loaded, memory first touched), about 10 % of a 1 kHz episode.
    instrumented, timed = _run(period_s, goal, state, metrics, instrumented=True)
    plain, _ = _run(period_s, goal, state, metrics)
    episode = Episode(goal=goal, control_period_s=period_s, state=state)
    return {
        "name": (f"{1.0 / period_s:g} Hz, {'estimated' if state == 'estimate' else 'truth'}"
                 + (" + metrics hook" if metrics else "")),
        "state": state,
        "control_period_s": period_s,
        "physics_timestep_s": episode.timestep_s,
        "physics_steps_per_tick": round(period_s / episode.timestep_s),
        "hooks": ["MetricsHook"] if metrics else [],
        **plain,
        "per_tick_us": timed.breakdown(),
        "instrumented": {k: instrumented[k] for k in ("status", "ticks", "real_time_factor")},
    }


# ---------------------------------------------------------------------------- fresh process

#: A one-leg trajectory for the fresh-process run: FR's three joints to a step in 1 s.
FRESH_TRAJECTORY = (("FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"), (-0.1, 0.2, -1.6), 1.0)


def fresh_process_ticks(goal: HighFiveGoal) -> dict[str, dict[str, Any]]:
    """In this process (meant to be a new one): build the loop as ``go2-wbc`` does, then time
    every tick of its first settle standing and of one goal of each action (high five, a
    one-leg FollowJointTrajectory, sit, stand), one after the other on the same loop.

    The worst tick of a fresh process is where one-off work lands (compiled code loaded
    from numba's cache, a QP layout or solver structure built, a file read): on a robot it
    is a stalled control period. Returns per part: ticks, status, max, p99.9 and median [us].
    """
    names, positions, seconds = FRESH_TRAJECTORY
    trajectory = JointTrajectory(joint_names=list(names), points=[
        JointTrajectoryPoint(positions=list(positions), time_from_start=seconds)])
    # Each goal is sent at once, on the loop as the previous one left it.
    episodes = {"first ticks (standing)": Episode(action=None, settle_s=0.0,
                                                  after_s=episode_default("settle_s")),
                "high_five": Episode(goal=goal, settle_s=0.0),
                "follow_joint_trajectory": Episode(
                    action="follow_joint_trajectory", settle_s=0.0,
                    goal=FollowJointTrajectoryGoal(trajectory=trajectory)),
                "sit": Episode(action="sit", goal=SitGoal(), settle_s=0.0),
                "stand": Episode(action="stand", goal=StandGoal(), settle_s=0.0)}
    clock = time.perf_counter
    start = clock()
    loop = build_loop(episodes["high_five"])
    parts: dict[str, dict[str, Any]] = {"construction": {"wall_ms": (clock() - start) * 1e3}}
    ticks: list[float] = []

    def timed() -> None:
        begin = clock()
        loop.spin_once()
        ticks.append(clock() - begin)

    # As go2-wbc runs its loop: start-up's objects out of the collector's scans (a full
    # collection of them, 115 to 155 ms here, landed in one goal's tick without this).
    with startup_objects_frozen():
        for part, episode in episodes.items():
            ticks.clear()
            result = EpisodeRunner(episode, loop=loop).run(tick=timed)
            status = "SUCCEEDED" if result.status == NO_GOAL else result.status
            parts[part] = _tick_stats(list(ticks), status)
    return parts


def _tick_stats(seconds: list[float], status: str) -> dict[str, Any]:
    values = np.sort(np.asarray(seconds)) * 1e6
    return {"status": status, "ticks": int(values.size), "max_us": float(values[-1]),
            "p999_us": float(values[int(0.999 * (values.size - 1))]),
            "median_us": float(np.median(values))}


def run_fresh_process(quick: bool) -> dict[str, dict[str, Any]]:
    """:func:`fresh_process_ticks` in a new interpreter (this one has loaded everything)."""
    command = [sys.executable, "-m", "benchmarks.loop_timing", "--fresh-process-child"]
    if quick:
        command.append("--quick")
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run(command, cwd=root, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"the fresh-process run failed: {done.stderr[-2000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def run(*, quick: bool = False, log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Every run; the report as a dict."""
    defaults = episode_defaults()
    hold = QUICK_HOLD_S if quick else defaults["hold_seconds"]
    goal = HighFiveGoal(target_height=defaults["target_height"], hold_seconds=hold)
    plant = defaults["plant"]
    plan = [(p, False, state) for p in PERIODS_S for state in STATES]
    plan += [] if quick else [(PERIODS_S[0], True, "estimate")]
    runs = []
    for period_s, metrics, state in plan:
        log(f"{1.0 / period_s:g} Hz on the {state}{' with the metrics hook' if metrics else ''}")
        runs.append(run_rate(period_s, goal, metrics=metrics, state=state))
    ratios = {}
    for period_s in PERIODS_S:
        rtf = {r["state"]: r["real_time_factor"] for r in runs
               if r["control_period_s"] == period_s and not r["hooks"]}
        ratios[f"{1.0 / period_s:g} Hz"] = rtf["estimate"] / rtf["truth"]
    log("a fresh process: its first ticks and each action's first goal")
    fresh = run_fresh_process(quick)
    return {
        "machine": machine(PACKAGES, with_platform=False),
        "mode": "quick" if quick else "full",
        "episode": {"action": "high_five", "target_height_m": goal.target_height,
                    "hold_seconds": goal.hold_seconds, "plant": plant.name,
                    "settle_s": defaults["settle_s"],
                    "cli_defaults": {"target_height_m": defaults["target_height"],
                                     "hold_seconds": defaults["hold_seconds"],
                                     "control_rate_hz": defaults["control_rate_hz"]}},
        "runs": runs,
        "estimate_over_truth_real_time_factor": ratios,
        "fresh_process": fresh,
        "notes": [
            ("Real-time factor: sim time over wall time from the goal's sending to its result, "
             "ControlLoop.spin_once as go2-wbc runs it; cpu share: process CPU time over that "
             "wall time."),
            ("Per-tick parts [us] from a second episode whose loop ticks with a stage timer "
             "(perf_counter at each stage's end; see the module docstring); physics.mj_step "
             "times the mujoco.mj_step calls of the tick; 'around controller' is the tick "
             "less controller.step. Medians do not add up: each is its own part's."),
            ("Fresh process: a new interpreter builds the loop and runs, at 1 kHz, its first "
             "ticks standing, then one goal of each action in turn (the high five above, FR's "
             "joints to a step in 1 s, sit, stand); where one-off work lands in a tick, its "
             "max shows it."),
        ],
    }


def format_report(report: dict[str, Any]) -> str:
    """The report as plain text: one line per run, then the per-tick parts."""
    m = report["machine"]
    versions = ", ".join(f"{k} {v}" for k, v in m["versions"].items() if v)
    e = report["episode"]
    lines = [(f"Machine: {m['cpu']}, {m['cores']} cores, load "
              f"{m['load_average_1_5_15_min'][0]:.2f} at start, Python {m['python']}; "
              f"{versions}"),
             (f"Mode: {report['mode']}. high five to {e['target_height_m']:.2f} m, hold "
              f"{e['hold_seconds']} s, plant {e['plant']}, after standing {e['settle_s']:g} s"),
             ""]
    head = f"{'run':<26}{'status':>10}{'ticks':>7}{'sim s':>7}{'wall s':>8}{'RTF':>7}{'cpu':>6}"
    lines += ["Whole episode (ControlLoop.spin_once)", head, "-" * len(head)]
    for r in report["runs"]:
        lines.append(f"{r['name']:<26}{r['status']:>10}{r['ticks']:>7}{r['sim_s']:>7.2f}"
                     f"{r['wall_s']:>8.2f}{r['real_time_factor']:>7.2f}"
                     f"{r['cpu_share']:>6.2f}")
    lines.append("real-time factor on the estimate over the truth's: " + ", ".join(
        f"{rate} {ratio:.2f}" for rate, ratio in
        report["estimate_over_truth_real_time_factor"].items()))
    for r in report["runs"]:
        lines += ["", (f"Per tick [us], {r['name']} (instrumented episode: RTF "
                       f"{r['instrumented']['real_time_factor']:.2f})"),
                  f"{'part':<26}{'median':>8}{'p99':>8}{'mean':>8}"]
        for part, s in r["per_tick_us"].items():
            name = f"  {part.split('.', 1)[1]}" if "." in part else part
            lines.append(f"{name:<26}{s['median']:>8.1f}{s['p99']:>8.1f}{s['mean']:>8.1f}")
    fresh = report["fresh_process"]
    lines += ["", (f"Fresh process (loop built in {fresh['construction']['wall_ms']:.0f} ms): "
                   "worst ticks [us]"),
              f"{'part':<26}{'status':>10}{'ticks':>7}{'median':>8}{'p99.9':>8}{'max':>8}"]
    for part, s in fresh.items():
        if part != "construction":
            lines.append(f"{part:<26}{s['status']:>10}{s['ticks']:>7}{s['median_us']:>8.0f}"
                         f"{s['p999_us']:>8.0f}{s['max_us']:>8.0f}")
    return "\n".join(lines + [""] + report["notes"])


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.loop_timing",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"hold the foot {QUICK_HOLD_S} s and skip the metrics-hook run")
    parser.add_argument("--json", type=Path, default=Path("out/loop_timing.json"),
                        help="where to write the report (default: out/loop_timing.json)")
    parser.add_argument("--fresh-process-child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.fresh_process_child:  # the fresh-process run's child: one JSON line
        defaults = episode_defaults()
        hold = QUICK_HOLD_S if args.quick else defaults["hold_seconds"]
        goal = HighFiveGoal(target_height=defaults["target_height"], hold_seconds=hold)
        print(json.dumps(fresh_process_ticks(goal)))
        return 0
    return run_and_report(lambda log: run(quick=args.quick, log=log),
                          format_report, args.json)


if __name__ == "__main__":
    raise SystemExit(main())
