"""Robustness and tuning sweeps of the high five: pushes, plant parameters and gains, on Ray.

Run ``python -m benchmarks.sweep [SPEC] [ranges] [--executor ...] [--address ...]``.

A sweep (:mod:`benchmarks.sweep_spec`: a YAML file, a built-in name, ranges on the command
line) is the product of its fields' values; each combination is one episode (a 0.40 m high
five, pushed during its hold, on a plant, with gains), and each episode one task:

- on Ray (``pip install 'go2-wbc[scale]'``): a local instance using every core, or a cluster
  with ``--address``;
- without Ray, in a local process pool (and it says how to get Ray); ``--executor serial``
  runs them in turn in this process.

Every episode is deterministic (simulated time, fixed seeds), so the executors give the same
results. A progress bar shows the episodes done, the failures so far and the time left. Each
result is appended to a JSON Lines file as it arrives (:mod:`benchmarks.sweep_results`); run
the same command again after an interrupt and it resumes: episodes are keyed by their full
specification, and finished ones are not run again. At the end it prints the outcome tables
and draws heat maps (:mod:`benchmarks.sweep_report`).
"""

from __future__ import annotations

import argparse
import signal
import sys
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

from benchmarks.sweep_report import SweepReport, outcome_of
from benchmarks.sweep_results import SweepResults, SweepResultsError
from benchmarks.sweep_runner import EXECUTORS, SweepRunner
from benchmarks.sweep_spec import (
    BUILT_IN,
    DEFAULT_SWEEP,
    DIRECTIONS,
    IMPULSES,
    EpisodeSpec,
    SweepSpec,
    value_text,
)
from benchmarks.sweep_values import cli_values
from sim.episode import episode_default
from wbc.core.errors import ConfigurationError

#: Exit statuses: done; an episode raised (its record says what; run again to retry);
#: usage error; interrupted (run again to resume).
EXIT_OK, EXIT_EPISODE_ERRORS, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130
#: Where results go unless ``--results`` says: ``out/sweep/<spec name>.jsonl``.
RESULTS_DIR = Path("out/sweep")


@dataclass
class SweepRun:
    """What :func:`run_sweep` did."""

    spec: SweepSpec
    #: Records of this sweep's episodes by key (finished, or with the error they raised).
    records: dict[str, dict[str, Any]]
    #: Distinct episodes (equal specifications run once), and how many were on file.
    episodes: int
    resumed: int
    #: Episodes run now, and the wall time [s] they took.
    ran: int
    wall_s: float
    #: The executor as it ran: ``Ray (local instance, 2 CPUs)``...
    executor: str

    @property
    def report(self) -> SweepReport:
        """The tables and heat maps of these results."""
        return SweepReport(self.spec, self.records)


def unique_episodes(spec: SweepSpec) -> list[EpisodeSpec]:
    """The spec's episodes, each specification once (e.g. every direction of a zero push)."""
    seen: dict[str, EpisodeSpec] = {}
    for episode in spec.episodes():
        seen.setdefault(episode.key, episode)
    return list(seen.values())


def run_sweep(spec: SweepSpec, results: SweepResults, runner: SweepRunner, *,
              fresh: bool = False, progress: bool = True,
              log: Callable[[str], None] = print) -> SweepRun:
    """Run the episodes of ``spec`` that ``results`` does not hold yet; append each result.

    Args:
        spec: The sweep.
        results: Its results file, read to resume and appended to as results arrive.
        runner: Where the episodes run.
        fresh: Remove the results file first (run every episode again).
        progress: Show a progress bar (on standard error).
        log: Where the messages go (resume, fallback from Ray, failed episodes).

    Raises:
        KeyboardInterrupt: The sweep was interrupted; what finished is on file.
        SweepResultsError: The results file has a damaged line (not the last).
    """
    episodes = unique_episodes(spec)
    if fresh:
        results.clear()
    on_file = results.load()
    if results.truncated_line:
        log(f"{results.path}: removed an unfinished last line (the sweep was killed while "
            f"writing it)")
    records = {e.key: on_file[e.key] for e in episodes if e.key in on_file}
    todo = [e for e in episodes if e.key not in records]
    if runner.note:
        log(runner.note)
    if records:
        log(f"resuming: {len(records)} of {len(episodes)} episodes are in {results.path}; "
            f"running the other {len(todo)}")
    counts = Counter(outcome_of(r) for r in records.values())
    bar = _progress_bar(total=len(episodes), initial=len(records), desc=spec.name,
                        enabled=progress, log=log)
    bar.set_postfix_str(_failures(counts), refresh=False)

    def on_done(episode: EpisodeSpec, outcome: dict[str, Any]) -> None:
        record = {"key": episode.key, "axes": episode.axes, **outcome,
                  "spec": episode.resolved()}
        results.append(record)
        records[episode.key] = record
        counts[outcome_of(record)] += 1
        if "error" in outcome:  # above the bar, on standard error
            bar.write(f"episode {episode.label() or spec.name} failed: {outcome['error']}",
                      file=sys.stderr)
        bar.set_postfix_str(_failures(counts), refresh=False)
        bar.update(1)

    started = time.perf_counter()
    try:
        runner.run(todo, on_done)
    finally:
        bar.close()
    return SweepRun(spec=spec, records=records, episodes=len(episodes),
                    resumed=len(episodes) - len(todo), ran=len(todo),
                    wall_s=time.perf_counter() - started, executor=runner.description)


class _NoBar:
    """Stands in for the progress bar when there is none; messages still go to the log."""

    def __init__(self, log: Callable[[str], None]) -> None:
        self.log = log

    def write(self, text: str, file: Any = None) -> None:
        """A message, to the log."""
        self.log(text)

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        """Nothing to show."""

    def update(self, n: int = 1) -> None:
        """Nothing to show."""

    def close(self) -> None:
        """Nothing to close."""


def _progress_bar(*, total: int, initial: int, desc: str, enabled: bool,
                  log: Callable[[str], None]) -> Any:
    """tqdm's bar on standard error: episodes done, rate and time left (none if disabled)."""
    if not enabled:
        return _NoBar(log)
    try:
        from tqdm import tqdm
    except ImportError:
        log("no progress bar: tqdm is not installed (pip install tqdm)")
        return _NoBar(log)
    return tqdm(total=total, initial=initial, desc=desc, unit="episode", file=sys.stderr,
                dynamic_ncols=True, mininterval=0.5)


def _failures(counts: Counter[str]) -> str:
    text = f"fell {counts['F']}, aborted {counts['A']}"
    return text + (f", errors {counts['E']}" if counts["E"] else "")


# ---------------------------------------------------------------------------- command line


class _Parser(argparse.ArgumentParser):
    """A usage error on one line, naming the field or option: ``pushes.impulses_ns: ...``."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def _assignment(option: str, section: str) -> Callable[[str], tuple[str, Any]]:
    def parse(text: str) -> tuple[str, Any]:
        name, sep, values = text.partition("=")
        if not sep or not name.strip() or not values.strip():
            example = {"gains": "swing_kp=40:60:3", "plant": "payload_kg=0,2"}.get(section,
                                                                                   "hold_s=1,2")
            raise argparse.ArgumentTypeError(
                f"expected NAME=VALUES (e.g. {example}), received {text!r}")
        name = name.strip()
        path = name if section == "" else f"{section}.{name}"
        return path, cli_values(values)

    parse.__name__ = option
    return parse


def build_parser() -> argparse.ArgumentParser:
    """The command line (see ``--help``)."""
    parser = _Parser(
        prog="python -m benchmarks.sweep", description=__doc__.splitlines()[0],
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="VALUES: one value, a comma-separated list (0,45,90) or a range START:STOP:NUM "
               "(2:10:5: 2, 4, 6, 8, 10); three-number fields take [X,Y,Z] or "
               "[[X,Y,Z],[X,Y,Z]].\n\nexamples:\n"
               "  python -m benchmarks.sweep quick\n"
               "  python -m benchmarks.sweep pushes --impulses 2:10:5 --plant payload_kg=0,2\n"
               "  python -m benchmarks.sweep my_sweep.yaml --gain swing_kp=30:60:4 "
               "--executor process\n"
               "  python -m benchmarks.sweep my_sweep.yaml --address auto   # on a Ray cluster")
    parser.add_argument("spec", nargs="?", default=DEFAULT_SWEEP,
                        help=f"a YAML file, or a built-in sweep: {', '.join(BUILT_IN)} "
                             f"(default: {DEFAULT_SWEEP})")
    grid = parser.add_argument_group("ranges (replace the spec's field)")
    grid.add_argument("--directions", metavar="VALUES", type=cli_values,
                      help="push directions [deg] (0 forward, 90 left)")
    grid.add_argument("--impulses", metavar="VALUES", type=cli_values,
                      help="push impulses [N s] (0.1 s pushes, 0.2 s into the hold)")
    grid.add_argument("--plant", metavar="NAME=VALUES", action="append", default=[],
                      type=_assignment("--plant", "plant"),
                      help="a plant parameter (sim.plant.Plant: joint_damping, "
                           "joint_friction_loss, calf_friction_loss, foot_friction, payload_kg, "
                           "...), preset, delay_ticks or control_period_s; repeatable")
    grid.add_argument("--sensors", metavar="NAME=VALUES", action="append", default=[],
                      type=_assignment("--sensors", "sensors"),
                      help="a sensor parameter (sim.sensors.SensorModel: gyro_noise_rad_s, "
                           "accel_bias_m_s2, joint_velocity_noise_rad_s, foot_force_gain, ...), "
                           "preset (go2, exact) or state (estimate, truth); repeatable")
    grid.add_argument("--gain", metavar="NAME=VALUES", action="append", default=[],
                      type=_assignment("--gain", "gains"),
                      help="a wbc.ControllerConfig field (swing_kp, stance_kd, com_kp, "
                           "foot_weight, ...); repeatable")
    grid.add_argument("--set", metavar="FIELD=VALUES", action="append", default=[],
                      type=_assignment("--set", ""),
                      help="any field by its path: hold_s, height_m, seed, metrics, "
                           "pushes.duration_s, pushes.into_hold_s; repeatable")
    run = parser.add_argument_group("running")
    run.add_argument("--executor", choices=EXECUTORS, default="auto",
                     help="auto: Ray when installed, else process (default: auto)")
    run.add_argument("--jobs", type=int, metavar="N",
                     help="episodes at once (default: every core; with --address, the "
                          "cluster's CPUs)")
    run.add_argument("--address", metavar="ADDRESS",
                     help="a Ray cluster: auto (on a node of it), HOST:6379, or "
                          "ray://HOST:10001 (Ray Client); default: a local Ray instance")
    run.add_argument("--results", type=Path, metavar="PATH",
                     help=f"the JSON Lines results, read to resume (default: "
                          f"{RESULTS_DIR}/<spec name>.jsonl)")
    run.add_argument("--plot", type=Path, metavar="PATH",
                     help="the heat map PNG (default: the results' path with .png)")
    run.add_argument("--fresh", action="store_true",
                     help="remove the results file first: run every episode again")
    run.add_argument("--no-progress", action="store_true", help="no progress bar")
    run.add_argument("--dry-run", action="store_true",
                     help="check the spec, print its fields and the number of episodes, stop")
    return parser


def _spec(args: argparse.Namespace) -> SweepSpec:
    spec = SweepSpec.load(args.spec)
    overrides: dict[str, Any] = {}
    if args.directions is not None:
        overrides[DIRECTIONS] = args.directions
    if args.impulses is not None:
        overrides[IMPULSES] = args.impulses
    for path, value in (*args.plant, *args.sensors, *args.gain, *args.set):
        overrides[path] = value
    return spec.with_values(overrides) if overrides else spec


def state_line(spec: SweepSpec) -> str:
    """Where the episodes' controller state comes from, and which sensors."""
    def values(path: str, default: str) -> str:
        axis = spec.axis(path)
        return default if axis is None else ", ".join(value_text(v) for v in axis.values)

    return (f"state: {values('sensors.state', episode_default('state'))} "
            f"({episode_default('estimator')} when estimated), sensors "
            f"{values('sensors.preset', episode_default('sensors'))}; measured on the "
            "simulator's truth")


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        spec = _spec(args)
        runner = SweepRunner(args.executor, jobs=args.jobs, address=args.address)
    except ConfigurationError as err:
        parser.error(_option(str(err)))
    episodes = unique_episodes(spec)
    print(state_line(spec))
    if args.dry_run:
        print(f"{spec.name}: {len(episodes)} episodes")
        for axis in spec.axes:
            print(f"  {axis.path}: {', '.join(value_text(v) for v in axis.values)}")
        return EXIT_OK
    results = SweepResults(args.results or RESULTS_DIR / f"{spec.name}.jsonl")
    plot = args.plot or results.path.with_suffix(".png")
    log = _stderr
    # A `kill` ends the sweep as Ctrl-C does: Ray or the pool shut down, the results stand.
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        run = run_sweep(spec, results, runner, fresh=args.fresh,
                        progress=not args.no_progress, log=log)
    except SweepResultsError as err:
        parser.error(str(err))
    except ConfigurationError as err:  # e.g. no Ray cluster at --address
        parser.error(_option(str(err)))
    except KeyboardInterrupt:
        done = len(set(results.load()) & {e.key for e in episodes})
        log(f"interrupted: {done} of {len(episodes)} episodes are in {results.path}; run the "
            f"same command again to resume")
        return EXIT_INTERRUPTED
    report = run.report
    print(report.table())
    print(f"\n{run.episodes} episodes: {run.ran} run in {run.wall_s:.1f} s wall on "
          f"{run.executor}" + (f", {run.resumed} already in {results.path}" if run.resumed
                               else ""))
    report.write_heat_map(plot)
    print(f"Wrote {results.path} and {plot}")
    errors = report.counts()["E"]
    if errors:
        them = "them" if errors > 1 else "it"
        log(f"{errors} episode{'s' if errors > 1 else ''} raised an error (see 'error' in "
            f"{results.path}); run the same command again to retry {them}")
        return EXIT_EPISODE_ERRORS
    return EXIT_OK


def _option(message: str) -> str:
    """``jobs: ...`` -> ``--jobs: ...`` (the runner's fields are options here)."""
    for name in ("executor", "jobs", "address"):
        if message.startswith(f"{name}:"):
            return f"--{message}"
    return message


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt


def _stderr(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
