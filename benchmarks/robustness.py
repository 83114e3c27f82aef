"""Robustness of the high five: pushes during the hold, and plants unlike the controller's model.

Run ``python -m benchmarks.robustness [--quick] [--json PATH] [--jobs N]``.

Measured in closed loop through the public API (each run a :class:`sim.episode.Episode` run
by :class:`sim.episode_runner.EpisodeRunner`: the default :class:`wbc.WholeBodyController`,
a HighFive goal of 0.40 m), on the default ``menagerie`` plant unless a row says otherwise
(the rows' plants: :mod:`benchmarks.plant_cases`):

1. Pushes on the base during a 1 s hold: direction x impulse (0.1 s pushes, starting 0.2 s
   into the hold) -> S (SUCCEEDED), A (ABORTED with the robot up), F (fell: the base came
   down to 0.2 m, or ended below standing height or tilted beyond 12 deg).
2. Plant changes (:class:`sim.plant.Plant` presets and parameters, sensor noise and control
   delay through :class:`sim.disturbances.DelayedRobot`), 1 s hold: outcome,
   raised-foot tracking, stance sliding, lowest base, largest tilt.
3. The joint sweep, 2 s hold: joint damping {0, 0.5, 1, 2, 3} N m s/rad x friction loss
   {0, 0.2, 0.4} N m x payload {none, 2 kg 5 cm in front of the base's centre}.
4. The calf sweep, 2 s hold, on the ``identified`` joints: calf friction loss
   {0.2, 0.5, 1.0, 1.4} N m x joint damping {0.1, 0.3, 2} x payload {none, 2 kg}.

Every table's episodes run in parallel processes (``--jobs``); ``python -m benchmarks.sweep``
runs larger grids of pushes, plant parameters and gains (on Ray when installed). Every run
is seeded and in simulated time: the same settings give the same tables. ``--quick`` runs a
2 x 2 corner of the push grid, two plant changes and the hardest corner of each sweep.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import multiprocessing
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from actions.go2.robot_context import STANDING_HEIGHT_M, TILT_LIMIT_DEG, tilt_deg
from actions.goal_status import GoalStatus
from benchmarks.plant_cases import (
    CALF_SWEEP,
    COMPENSATION_CASES,
    JOINT_SWEEP,
    NOMINAL_CASE,
    PLANT_CASES,
    QUICK_CALF_SWEEP,
    QUICK_JOINT_SWEEP,
    QUICK_PLANT_CASES,
    SWEEP_HOLD_S,
    PlantCase,
    controller_parts,
)
from benchmarks.reporting import machine, run_and_report
from benchmarks.robustness_report import format_report
from sim.control_loop import ControlLoop, TickHook
from sim.disturbances import Push
from sim.episode import Episode, episode_default
from sim.episode_loop import build_loop
from sim.episode_metrics import EpisodeSummary
from sim.episode_runner import EpisodeRunner
from wbc.controller.balance_controller import BalanceController
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import WbcError
from wbc.model.description import LEGS
from wbc.motions.leg_lift import LegLiftTiming

#: The high five: the default episode's height [m], and a 1 s hold [s].
HEIGHT_M, HOLD_S = episode_default("goal").target_height, 1
#: The robot stands this long [s] before the goal is sent (the default episode's settle).
SETTLE_S = episode_default("settle_s")
#: The hold starts this long [s] after the goal (shift, unload, raise).
HOLD_START_S = LegLiftTiming().shift_s + LegLiftTiming().unload_s + LegLiftTiming().raise_s
#: Pushes start this long [s] into the hold and last PUSH_DURATION_S [s].
PUSH_INTO_HOLD_S, PUSH_DURATION_S = 0.2, 0.1
#: The loop runs on this long [s] after the result, to see where the robot comes to rest.
AFTER_S = 0.5
#: Sim time [s] a goal may take before the run cancels it.
TIMEOUT_S = 30.0
#: Below this base height [m], at any time, the robot has fallen.
FALLEN_HEIGHT_M = 0.2
#: A foot carrying more than this [N] counts as loaded when judging "standing".
LOADED_N = 5.0

DIRECTIONS_DEG = tuple(range(0, 360, 45))
IMPULSES_NS = (2.0, 4.0, 6.0, 8.0, 10.0)
QUICK_DIRECTIONS_DEG = (90, 315)
QUICK_IMPULSES_NS = (4.0, 8.0)


@dataclass
class HighFiveOutcome:
    """What one high five did, measured tick by tick from the goal to the end of the run."""

    status: GoalStatus
    message: str
    #: Lowest and final base height [m], largest and final base tilt [deg].
    min_height_m: float
    final_height_m: float
    max_tilt_deg: float
    final_tilt_deg: float
    #: At the end: four feet in stance in the controller and loaded in MuJoCo, base at
    #: standing height and level within 5 deg.
    standing: bool
    #: The episode's quality metrics (``None`` when the run was not measured).
    summary: EpisodeSummary | None
    #: Sim time [s] the goal was sent.
    start_s: float = 0.0
    #: Feedback phases with the sim time [s] they were received, counted from ``start_s``.
    phases: list[tuple[float, str]] = field(default_factory=list)
    loop: ControlLoop | None = field(default=None, repr=False)

    @property
    def fell(self) -> bool:
        """The base came down to ``FALLEN_HEIGHT_M``, or ended low or tilted beyond the limit."""
        return (self.min_height_m < FALLEN_HEIGHT_M or self.final_height_m < STANDING_HEIGHT_M
                or self.final_tilt_deg > TILT_LIMIT_DEG
                or (self.summary is not None and self.summary.fell))

    @property
    def outcome(self) -> str:
        """``S`` succeeded, ``A`` aborted with the robot up, ``F`` fell."""
        if self.fell:
            return "F"
        return "S" if self.status is GoalStatus.SUCCEEDED else "A"

    def row(self) -> dict[str, Any]:
        """Plain values, JSON-ready (the metrics only when the run was measured)."""
        row = {"outcome": self.outcome, "status": self.status.name, "message": self.message,
               "min_height_m": round(self.min_height_m, 4),
               "final_height_m": round(self.final_height_m, 4),
               "max_tilt_deg": round(self.max_tilt_deg, 2),
               "final_tilt_deg": round(self.final_tilt_deg, 2), "standing": self.standing,
               "fell": self.fell}
        if self.summary is not None:
            s = self.summary
            row.update(tracking_rms_mm=round(s.raised_foot_rms_mm, 3),
                       holding_rms_mm=round(s.holding_rms_mm, 3),
                       stance_sliding_max_mm=round(s.stance_sliding_max_mm, 3),
                       qp_failures=s.qp_failures)
        return row


class _Extremes:
    """Lowest base and largest tilt, tick by tick (a loop hook)."""

    def __init__(self) -> None:
        self.min_height_m = math.inf
        self.max_tilt_deg = 0.0

    def __call__(self, loop: ControlLoop, out: Any) -> None:
        q, _ = loop.true_state()
        self.min_height_m = min(self.min_height_m, float(q[2]))
        self.max_tilt_deg = max(self.max_tilt_deg, tilt_deg(q))


def standing_on_four_feet(loop: ControlLoop) -> bool:
    """Four feet in stance in the controller and loaded in MuJoCo, the base at standing
    height and level within 5 deg (the simulator's true state)."""
    q, _ = loop.true_state()
    forces = loop.sim.foot_contact_forces()
    return (len(loop.controller.stance_legs) == len(LEGS) and q[2] > STANDING_HEIGHT_M
            and tilt_deg(q) < 5.0 and all(forces[leg][2] > LOADED_N for leg in LEGS))


def make_loop(case: PlantCase = NOMINAL_CASE, *, seed: int = 0,
              controller: BalanceController | None = None,
              faults_from_s: float = SETTLE_S) -> ControlLoop:
    """A control loop on a fresh standing MuJoCo GO2 built with ``case``'s plant and sensors.

    ``seed`` seeds the sensors' noise and biases; the case's sensor faults start
    ``faults_from_s`` [s] later than their own times (a goal is sent at :data:`SETTLE_S`).
    """
    episode = case.episode(height_m=HEIGHT_M, hold_s=HOLD_S, seed=seed)
    shift = faults_from_s - SETTLE_S  # the case's episode starts its faults at SETTLE_S
    faults = tuple(dataclasses.replace(f, at_s=f.at_s + shift) for f in episode.sensor_faults)
    return build_loop(episode.replace(sensor_faults=faults), controller or WholeBodyController(
        solver={"control_period_s": case.control_period_s}))


def run_high_five(case: PlantCase = NOMINAL_CASE, *, pushes: Sequence[Push] = (),
                  hold_s: int = HOLD_S, height_m: float = HEIGHT_M, seed: int = 0,
                  hooks: Sequence[TickHook] = (), after_s: float = AFTER_S,
                  measure: bool = True, controller: BalanceController | None = None
                  ) -> HighFiveOutcome:
    """Stand ``SETTLE_S``, run one high five with ``pushes``, run on ``after_s``; measure it.

    Args:
        case: The plant, sensor noise and delay.
        pushes: Pushes whose ``at_s`` counts from the goal's start [s].
        hold_s: The goal's hold [s]. height_m: Its foot height [m].
        seed: Seed of the sensors' noise and biases.
        hooks: More loop hooks, called every tick from the goal on.
        after_s: How long [s] the loop runs on after the result.
        measure: Measure the episode with :class:`sim.episode_metrics.EpisodeMetrics`
            (tracking, sliding...; it costs about half the control's time).
        controller: The controller (a default :class:`WholeBodyController` when ``None``).
    """
    episode = case.episode(height_m=height_m, hold_s=hold_s, seed=seed, pushes=tuple(pushes),
                           after_s=after_s, timeout_s=TIMEOUT_S)
    return measured_high_five(episode, hooks=hooks, measure=measure, controller=controller)


def measured_high_five(episode: Episode, *, hooks: Sequence[TickHook] = (),
                       measure: bool = True, controller: BalanceController | None = None
                       ) -> HighFiveOutcome:
    """Run ``episode`` (a high five) and measure where the robot went, on the truth.

    Raises:
        WbcError: The goal ended without a result (rejected, or none within its timeout).
    """
    extremes = _Extremes()
    result = EpisodeRunner(episode, controller=controller, hooks=[extremes, *hooks],
                           metrics=measure).run()
    if result.wrapped is None:
        raise WbcError(f"the high five ended without a result ({result.status}): "
                       f"{result.message}")
    loop, start = result.loop, result.sent_s
    final, _ = loop.true_state()
    return HighFiveOutcome(
        status=result.wrapped.status, message=result.message,
        min_height_m=extremes.min_height_m, final_height_m=float(final[2]),
        max_tilt_deg=extremes.max_tilt_deg, final_tilt_deg=tilt_deg(final),
        standing=standing_on_four_feet(loop), summary=result.metrics, start_s=start,
        phases=[(round(t_s - start, 4), phase) for t_s, phase in result.phases()], loop=loop)


def hold_push(direction_deg: float, impulse_ns: float, *, body: str = "base",
              duration_s: float = PUSH_DURATION_S, into_hold_s: float = PUSH_INTO_HOLD_S) -> Push:
    """A horizontal push of ``impulse_ns`` [N s] over ``duration_s`` [s], during the hold."""
    return Push(at_s=HOLD_START_S + into_hold_s, force_n=impulse_ns / duration_s,
                duration_s=duration_s, direction_deg=direction_deg, body=body)


def run_episode(case: PlantCase = NOMINAL_CASE, *, push: Push | None = None,
                hold_s: int = HOLD_S, height_m: float = HEIGHT_M, seed: int = 0,
                measure: bool = True, gains: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """One high five as a JSON-ready row (:meth:`HighFiveOutcome.row`): what every table and
    sweep runs.

    Args:
        case: The plant, sensor noise, delay and control period.
        push: A push whose ``at_s`` counts from the goal's start [s] (see :func:`hold_push`).
        hold_s: The goal's hold [s]. height_m: Its foot height [m].
        seed: Seed of the sensors' noise and biases.
        measure: Add the tracking, sliding and QP-failure metrics to the row.
        gains: :class:`wbc.ControllerConfig` parameters for the controller by their bare
            names, as a sweep file's ``gains`` (checked there); the default controller when
            empty.
    """
    episode = high_five_episode(case, push=push, hold_s=hold_s, height_m=height_m, seed=seed,
                                gains=gains)
    controller = None
    if gains:
        controller = WholeBodyController(**controller_parts(
            gains, control_period_s=case.control_period_s))
    return measured_high_five(episode, measure=measure, controller=controller).row()


def high_five_episode(case: PlantCase = NOMINAL_CASE, *, push: Push | None = None,
                      hold_s: int = HOLD_S, height_m: float = HEIGHT_M, seed: int = 0,
                      gains: Mapping[str, Any] | None = None) -> Episode:
    """The episode :func:`run_episode` runs (its goal, push, settle, run-on and timeout)."""
    return case.episode(height_m=height_m, hold_s=hold_s, seed=seed,
                        pushes=() if push is None else (push,), gains=dict(gains or {}),
                        after_s=AFTER_S, timeout_s=TIMEOUT_S)


# ---------------------------------------------------------------------------- the tables


def run(*, quick: bool, log: Callable[[str], None] = print,
        jobs: int | None = None) -> dict[str, Any]:
    """Run every table; returns the report (JSON-ready).

    The episodes run in ``jobs`` processes (default: every core); each episode is
    deterministic, so the rows do not depend on it.
    """
    directions = QUICK_DIRECTIONS_DEG if quick else DIRECTIONS_DEG
    impulses = QUICK_IMPULSES_NS if quick else IMPULSES_NS
    pushes = [(direction, impulse) for impulse in impulses for direction in directions]
    with process_pool(jobs, preload=[__name__]) as pool:
        cells = list(pool.map(push_cell, pushes))
    for cell in cells:
        log(f"push {cell['impulse_ns']:g} N s toward {cell['direction_deg']} deg: "
            f"{cell['outcome']} ({cell['status']}, lowest base {cell['min_height_m']:.3f} m)")
    outcomes = [cell["outcome"] for cell in cells]
    grid = {
        "directions_deg": list(directions), "impulses_ns": list(impulses),
        "duration_s": PUSH_DURATION_S, "starts_into_hold_s": PUSH_INTO_HOLD_S, "cells": cells,
        "succeeded": outcomes.count("S"), "aborted": outcomes.count("A"),
        "fell": outcomes.count("F"), "success_rate": outcomes.count("S") / len(outcomes),
        "any_fall": "F" in outcomes,
    }
    with process_pool(jobs, preload=[__name__]) as pool:
        plants = list(pool.map(plant_row, QUICK_PLANT_CASES if quick else PLANT_CASES))
    for row in plants:
        log(f"{row['name']}: {row['outcome']} ({row['status']})")
    sweeps = {}
    for name, cases in (("joint_sweep", QUICK_JOINT_SWEEP if quick else JOINT_SWEEP),
                        ("calf_sweep", QUICK_CALF_SWEEP if quick else CALF_SWEEP)):
        started = time.perf_counter()
        with process_pool(jobs, preload=[__name__]) as pool:
            rows = list(pool.map(sweep_row, cases))
        for row in rows:
            log(f"{name} {row['name']}: {row['outcome']} ({row['status']}), tilt "
                f"{row['max_tilt_deg']:.2f} deg")
        sweeps[name] = {"rows": rows, "wall_s": round(time.perf_counter() - started, 1),
                        "succeeded": sum(r["status"] == "SUCCEEDED" for r in rows),
                        "max_tilt_deg": max(r["max_tilt_deg"] for r in rows),
                        "max_final_tilt_deg": max(r["final_tilt_deg"] for r in rows)}
    if not quick:
        runs = [(case, informed) for case in COMPENSATION_CASES for informed in (False, True)]
        with process_pool(jobs, preload=[__name__]) as pool:
            sweeps["compensation"] = {"rows": list(pool.map(compensation_row, runs))}
    return {"mode": "quick" if quick else "full", "machine": machine(),
            "goal": {"target_height_m": HEIGHT_M, "hold_s": HOLD_S}, "push_grid": grid,
            "plant_changes": plants, **sweeps}


def process_pool(workers: int | None, *, preload: Sequence[str] = ()) -> ProcessPoolExecutor:
    """A pool of ``workers`` processes (default: every core) that does not fork this process.

    Forking a process that runs threads (numba's, Ray's, the viewer's) may deadlock the child,
    and Python 3.12 warns of it: the workers are forked from a clean forkserver that has
    imported ``preload`` once, or spawned where there is no forkserver.
    """
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(list(preload))
    else:
        context = multiprocessing.get_context("spawn")
    return ProcessPoolExecutor(max_workers=workers, mp_context=context)


def push_cell(push: tuple[float, float]) -> dict[str, Any]:
    """One cell of the push grid: ``(direction [deg], impulse [N s])`` -> its row, unmeasured."""
    direction, impulse = push
    row = run_episode(push=hold_push(direction, impulse), measure=False)
    return {"direction_deg": direction, "impulse_ns": impulse, **row}


def plant_row(case: PlantCase) -> dict[str, Any]:
    """One row of the plant table: the case's settings and its episode."""
    return {"name": case.name, "plant": dataclasses.asdict(case.plant),
            "delay_ticks": case.delay_ticks, "sensors": case.sensor_model().as_dict(),
            "state": case.state, **run_episode(case)}


def compensation_row(run: tuple[PlantCase, bool]) -> dict[str, Any]:
    """A sweep episode by the default controller, or by one told the plant's joint friction."""
    case, informed = run
    gains = {}
    if informed:
        joints = [getattr(case.plant, t) for t in ("hip", "thigh", "calf")]
        gains = {"known_joint_damping": tuple(j.damping for j in joints),
                 "known_joint_friction": tuple(j.friction_loss for j in joints)}
    return {"name": case.name, "known_friction": informed,
            **run_episode(case, hold_s=SWEEP_HOLD_S, gains=gains)}


def sweep_row(case: PlantCase) -> dict[str, Any]:
    """One sweep episode (a 0.40 m high five held :data:`SWEEP_HOLD_S`), as a report row."""
    return {"name": case.name, "plant": dataclasses.asdict(case.plant),
            **run_episode(case, hold_s=SWEEP_HOLD_S)}


def main(argv: Sequence[str] | None = None) -> int:
    """Command-line entry point."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.robustness",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="a 2 x 2 corner of the push grid and two plant changes")
    parser.add_argument("--json", type=Path, default=Path("out/robustness.json"),
                        help="where to write the report (default: out/robustness.json)")
    parser.add_argument("--jobs", type=int, default=None,
                        help="processes for the episodes (default: every core)")
    args = parser.parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        parser.error(f"--jobs: expected a whole number >= 1, received {args.jobs}")
    return run_and_report(lambda log: run(quick=args.quick, jobs=args.jobs, log=log),
                          format_report, args.json)


if __name__ == "__main__":
    raise SystemExit(main())
