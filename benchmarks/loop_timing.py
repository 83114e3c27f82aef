"""Whole-loop timing of ``go2-wbc high-five``: real-time factor and a per-tick breakdown.

Run ``python -m benchmarks.loop_timing [--quick] [--json PATH]``.

The episode is the command line's default high five (``go2-wbc high-five``: its height and
hold, the default plant and sensors, the controller on the estimated state, the robot
standing :data:`sim.cli.SETTLE_S` before the goal), at 1 kHz and at 500 Hz
(``control_period_s=2e-3``, two 1 ms physics steps per tick), and the same on the
simulator's exact state (``--state truth``) for comparison: the estimate's cost is the ratio
of the two real-time factors. Each rate and state gets two episodes on fresh loops, both
timed from the goal's sending to its result, as the command line times a run:

1. Per-tick breakdown: a loop of this module that calls the pieces ``spin_once`` calls, in
   its order, with ``time.perf_counter`` around each (listed below).
2. Real-time factor: ``ControlLoop.spin_once`` until the result, as the command line drives
   it; sim time over wall time, and the process's CPU time over that wall time (well below
   1: other processes took the cores). It runs second, so that it measures the loop rather
   than the one-off costs of the process's first goal (a fresh ``go2-wbc`` pays those:
   about 10 % more wall time at 1 kHz).

The parts of a tick:

- ``sensors``: ``robot.read_sensors()`` (the simulated sensors, their noise, the joint and
  leg orders); with ``--state truth``, ``robot.read_state()`` (MuJoCo to Pinocchio);
- ``estimator``: ``loop.estimate_state`` (the contact schedule, the state estimator's tick,
  the copies of ``q`` and ``v``); nothing with ``--state truth``;
- ``actions``: ``context.observe`` and ``runner.tick`` (the action servers and the
  behaviours: the high five's phases and balance watch);
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
import contextlib
import importlib.metadata
import json
import math
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from actions.messages import (
    FollowJointTrajectoryGoal,
    HighFiveGoal,
    JointTrajectory,
    JointTrajectoryPoint,
    SitGoal,
    StandGoal,
)
from sim.cli import SETTLE_S, build_parser
from sim.control_loop import PHYSICS_TIMESTEP_S, ControlLoop
from sim.plant import Plant
from sim.run_recorder import MetricsHook

#: Control periods [s] of the runs: 1 kHz and the GO2's usual 500 Hz.
PERIODS_S = (1e-3, 2e-3)
#: Parts of a tick, in the order the loop runs them (``rest`` is split around physics).
PARTS = ("sensors", "estimator", "actions", "controller", "rest", "physics")
#: Where the controller's state comes from in the runs, and the runs' order at each rate.
STATES = ("estimate", "truth")
#: The hold [s] of a quick run.
QUICK_HOLD_S = 0
PACKAGES = ("mujoco", "numpy", "numba", "pin", "daqp")
#: Sim time [s] after which a goal that has not ended counts as stuck.
GOAL_LIMIT_S = 60.0


def cli_defaults() -> dict[str, Any]:
    """What ``go2-wbc high-five`` runs with no options: goal, plant and rates."""
    args = build_parser().parse_args(["high-five"])
    plant = Plant.preset(args.plant).with_params(**dict(args.plant_param))
    return {"target_height": args.height, "hold_seconds": args.hold, "plant": plant,
            "control_rate_hz": args.control_rate, "settle_s": SETTLE_S}


def _build(period_s: float, plant: Plant, metrics: bool, state: str = "estimate"
           ) -> tuple[ControlLoop, list[str]]:
    """A standing loop at ``period_s`` as ``go2-wbc`` builds it, settled; and the list whose
    one entry the episode's feedback keeps at the goal's phase (for the metrics hook)."""
    loop = ControlLoop.simulated(pose="standing", plant=plant, control_period_s=period_s,
                                 physics_timestep_s=min(PHYSICS_TIMESTEP_S, period_s),
                                 state=state)
    loop.spin_for(SETTLE_S)
    phase = [""]
    if metrics:
        loop.hooks.append(MetricsHook(loop, lambda: phase[0]))
    return loop, phase


class _Episode:
    """One goal from its sending to its result; ``tick`` runs one control period."""

    def __init__(self, loop: ControlLoop, goal: Any, phase: list[str], *,
                 action: str = "high_five"):
        self.loop = loop
        self.phase = phase
        self.feedback = 0
        self.handle_future = loop.client(action).send_goal_async(
            goal, feedback_callback=self._on_feedback)
        self.result_future = None

    def _on_feedback(self, message: Any) -> None:
        self.feedback += 1
        self.phase[0] = getattr(message.feedback, "phase", "")  # FollowJointTrajectory's has none

    def done(self) -> bool:
        """Whether the result has come (or the goal was rejected)."""
        if self.result_future is None:
            if not self.handle_future.done():
                return False
            handle = self.handle_future.result()
            if not handle.accepted:
                return True
            self.result_future = handle.get_result_async()
        return self.result_future.done()

    def status(self) -> str:
        """The goal's final status name."""
        if self.result_future is None:
            return "REJECTED"
        return self.result_future.result().status.name


def _run(loop: ControlLoop, phase: list[str], goal: HighFiveGoal, tick: Callable[[], Any]
         ) -> dict[str, Any]:
    """Tick until the goal ends; sim time, wall time, CPU share."""
    episode = _Episode(loop, goal, phase)
    sim_start = loop.robot.time_s
    ticks = 0
    wall = time.perf_counter()
    cpu = time.process_time()
    while not episode.done():
        if loop.robot.time_s - sim_start > GOAL_LIMIT_S:
            raise RuntimeError(f"the goal did not end within {GOAL_LIMIT_S:g} s of sim time")
        tick()
        ticks += 1
    wall = time.perf_counter() - wall
    cpu = time.process_time() - cpu
    sim_s = loop.robot.time_s - sim_start
    return {"status": episode.status(), "ticks": ticks, "sim_s": sim_s, "wall_s": wall,
            "real_time_factor": sim_s / wall, "cpu_share": cpu / wall,
            "feedback_messages": episode.feedback}


class _TimedTicks:
    """The pieces of ``ControlLoop.spin_once``, called in its order and timed one by one.

    While :meth:`timing_mj_step` is active, ``mujoco.mj_step`` is wrapped to time each call
    (about 0.1 us added to ``physics``), so that ``physics.mj_step`` is the steps the loop
    really took, with the caches as the tick left them.
    """

    def __init__(self, loop: ControlLoop):
        self.loop = loop
        self.samples: dict[str, list[float]] = {p: [] for p in (*PARTS, "tick")}
        self.stages: dict[str, list[float]] = {}
        self.mj_step: list[float] = []
        self._stepped = 0.0  # seconds in mj_step since the last tick began

    @contextlib.contextmanager
    def timing_mj_step(self) -> Iterator[None]:
        """Time every ``mujoco.mj_step`` call inside the block."""
        step, clock = mujoco.mj_step, time.perf_counter

        def timed(*args: Any, **kwargs: Any) -> None:
            start = clock()
            step(*args, **kwargs)
            self._stepped += clock() - start

        mujoco.mj_step = timed
        try:
            yield
        finally:
            mujoco.mj_step = step

    def __call__(self) -> None:
        loop, clock = self.loop, time.perf_counter
        robot, context, controller = loop.robot, loop.context, loop.controller
        self._stepped = 0.0
        t0 = clock()
        now = robot.time_s
        if loop.estimator is None:
            q, v = robot.read_state()
            ts = clock()
        else:
            record = robot.read_sensors()
            ts = clock()
            q, v = loop.estimate_state(record)
        t1 = clock()
        context.observe(now, q, v)
        loop.runner.tick(now)
        t2 = clock()
        raw = loop.command(q, v)
        t3 = clock()
        out = loop.guard(raw, v)
        context.record_output(out)
        loop.last_output = out
        t4 = clock()
        robot.write_command(out)
        t5 = clock()
        for hook in loop.hooks:
            hook(loop, out)
        t6 = clock()
        for part, seconds in zip(PARTS, (ts - t0, t1 - ts, t2 - t1, t3 - t2,
                                         (t4 - t3) + (t6 - t5), t5 - t4)):
            self.samples[part].append(seconds)
        self.samples["tick"].append(t6 - t0)
        self.mj_step.append(self._stepped)
        for stage, seconds in raw.timings.items():
            self.stages.setdefault(stage, []).append(seconds)

    def breakdown(self) -> dict[str, dict[str, float]]:
        """Per-part statistics [us]; ``controller.<stage>`` and ``physics.mj_step`` below."""
        out = {part: _stats_us(self.samples[part])
               for part in ("sensors", "estimator", "actions", "controller")}
        out.update({f"controller.{k}": _stats_us(v) for k, v in self.stages.items()})
        out["physics"] = _stats_us(self.samples["physics"])
        out["physics.mj_step"] = _stats_us(self.mj_step)
        out["rest"] = _stats_us(self.samples["rest"])
        out["tick"] = _stats_us(self.samples["tick"])
        around = np.subtract(self.samples["tick"], self.samples["controller"])
        out["around controller"] = _stats_us(around)
        return out

def _stats_us(seconds: Sequence[float]) -> dict[str, float]:
    values = np.asarray(seconds, dtype=float) * 1e6
    if values.size == 0:
        return {"median": math.nan, "p99": math.nan, "mean": math.nan, "samples": 0}
    return {"median": float(np.median(values)), "p99": float(np.percentile(values, 99)),
            "mean": float(values.mean()), "samples": int(values.size)}


def run_rate(period_s: float, goal: HighFiveGoal, plant: Plant, *, metrics: bool = False,
             state: str = "estimate") -> dict[str, Any]:
    """The two episodes at one control period: the breakdown, then the real-time factor."""
    physics_s = min(PHYSICS_TIMESTEP_S, period_s)
    # The instrumented episode first: the process's first goal also pays one-off costs
    # (compiled code loaded, memory first touched), about 10 % of a 1 kHz episode.
    loop, phase = _build(period_s, plant, metrics, state)
    timed = _TimedTicks(loop)
    with timed.timing_mj_step():
        instrumented = _run(loop, phase, goal, timed)
    loop, phase = _build(period_s, plant, metrics, state)
    plain = _run(loop, phase, goal, loop.spin_once)
    return {
        "name": (f"{1.0 / period_s:g} Hz, {'estimated' if state == 'estimate' else 'truth'}"
                 + (" + metrics hook" if metrics else "")),
        "state": state,
        "control_period_s": period_s,
        "physics_timestep_s": physics_s,
        "physics_steps_per_tick": round(period_s / physics_s),
        "hooks": ["MetricsHook"] if metrics else [],
        **plain,
        "per_tick_us": timed.breakdown(),
        "instrumented": {k: instrumented[k] for k in ("status", "ticks", "real_time_factor")},
    }


# ---------------------------------------------------------------------------- fresh process

#: A one-leg trajectory for the fresh-process run: FR's three joints to a step in 1 s.
FRESH_TRAJECTORY = (("FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"), (-0.1, 0.2, -1.6), 1.0)


def fresh_process_ticks(goal: HighFiveGoal, plant: Plant) -> dict[str, dict[str, Any]]:
    """In this process (meant to be a new one): build the loop as ``go2-wbc`` does, then time
    every tick of its first :data:`SETTLE_S` standing and of one goal of each action
    (high five, a one-leg FollowJointTrajectory, sit, stand), one after the other.

    The worst tick of a fresh process is where one-off work lands (compiled code loaded
    from numba's cache, a QP layout or solver structure built, a file read): on a robot it
    is a stalled control period. Returns per part: ticks, status, max, p99.9 and median [us].
    """
    clock = time.perf_counter
    start = clock()
    loop = ControlLoop.simulated(pose="standing", plant=plant)
    parts: dict[str, dict[str, Any]] = {"construction": {"wall_ms": (clock() - start) * 1e3}}

    def timed(until: Callable[[], bool]) -> list[float]:
        ticks = []
        while not until():
            begin = clock()
            loop.spin_once()
            ticks.append(clock() - begin)
        return ticks

    end = loop.robot.time_s + SETTLE_S - 1e-9
    parts["first ticks (standing)"] = _tick_stats(timed(lambda: loop.robot.time_s >= end),
                                                  "SUCCEEDED")
    names, positions, seconds = FRESH_TRAJECTORY
    trajectory = JointTrajectory(joint_names=list(names), points=[
        JointTrajectoryPoint(positions=list(positions), time_from_start=seconds)])
    for action, message in (("high_five", goal),
                            ("follow_joint_trajectory",
                             FollowJointTrajectoryGoal(trajectory=trajectory)),
                            ("sit", SitGoal()), ("stand", StandGoal())):
        episode = _Episode(loop, message, [""], action=action)
        parts[action] = _tick_stats(timed(episode.done), episode.status())
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


def machine() -> dict[str, Any]:
    """CPU, cores, load, Python and the versions of the packages that matter here."""
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
            "load_average_1_5_15_min": list(os.getloadavg()), "versions": versions}


def run(*, quick: bool = False, log: Callable[[str], None] = lambda _: None) -> dict[str, Any]:
    """Every run; the report as a dict."""
    defaults = cli_defaults()
    hold = QUICK_HOLD_S if quick else defaults["hold_seconds"]
    goal = HighFiveGoal(target_height=defaults["target_height"], hold_seconds=hold)
    plant = defaults["plant"]
    plan = [(p, False, state) for p in PERIODS_S for state in STATES]
    plan += [] if quick else [(PERIODS_S[0], True, "estimate")]
    runs = []
    for period_s, metrics, state in plan:
        log(f"{1.0 / period_s:g} Hz on the {state}{' with the metrics hook' if metrics else ''}")
        runs.append(run_rate(period_s, goal, plant, metrics=metrics, state=state))
    ratios = {}
    for period_s in PERIODS_S:
        rtf = {r["state"]: r["real_time_factor"] for r in runs
               if r["control_period_s"] == period_s and not r["hooks"]}
        ratios[f"{1.0 / period_s:g} Hz"] = rtf["estimate"] / rtf["truth"]
    log("a fresh process: its first ticks and each action's first goal")
    fresh = run_fresh_process(quick)
    return {
        "machine": machine(),
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
            ("Per-tick parts [us] from a second episode whose loop calls spin_once's pieces "
             "with perf_counter around each (see the module docstring); physics.mj_step "
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


def _json_safe(value: Any) -> Any:
    """Non-finite numbers become ``null`` (JSON has no NaN)."""
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value


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
        defaults = cli_defaults()
        hold = QUICK_HOLD_S if args.quick else defaults["hold_seconds"]
        goal = HighFiveGoal(target_height=defaults["target_height"], hold_seconds=hold)
        print(json.dumps(fresh_process_ticks(goal, defaults["plant"])))
        return 0
    started = time.perf_counter()
    report = run(quick=args.quick, log=lambda msg: print(
        f"[{time.perf_counter() - started:6.1f} s] {msg}", file=sys.stderr, flush=True))
    report["benchmark_wall_s"] = time.perf_counter() - started
    print(format_report(report))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(_json_safe(report), indent=1, allow_nan=False))
    print(f"\nWrote {args.json} in {report['benchmark_wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
