"""Robustness of the high five: pushes during the hold, and plants unlike the controller's model.

Run ``python -m benchmarks.robustness [--quick] [--json PATH] [--jobs N]``.

Measured in closed loop through the public API (``sim.control_loop.ControlLoop`` with the
default :class:`wbc.WholeBodyController`, a HighFive goal of 0.40 m), on the default
``menagerie`` plant unless a row says otherwise:

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
import json
import math
import multiprocessing
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from actions.go2.robot_context import STANDING_HEIGHT_M, TILT_LIMIT_DEG, tilt_deg
from actions.goal_status import GoalStatus
from actions.messages import HighFiveGoal
from benchmarks.qp_timing import machine
from sim.cli import MetricsHook
from sim.control_loop import ControlLoop, TickHook
from sim.disturbances import Push, PushSchedule
from sim.episode_metrics import EpisodeSummary
from sim.plant import Plant
from sim.sensor_faults import SensorFault
from sim.sensors import DEFAULT_SENSORS, SensorModel
from wbc.controller.balance_controller import BalanceController
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.estimation.estimators import DEFAULT_ESTIMATOR, make_estimator
from wbc.model.description import LEGS
from wbc.motions.leg_lift import LegLiftTiming

HEIGHT_M, HOLD_S = 0.40, 1
#: The robot stands this long [s] before the goal is sent (the plant spawns without contact
#: forces; its feet settle in the first 20 ms).
SETTLE_S = 0.3
#: The hold starts this long [s] after the goal (shift, unload, raise).
HOLD_START_S = LegLiftTiming().shift_s + LegLiftTiming().unload_s + LegLiftTiming().raise_s
#: Pushes start this long [s] into the hold and last PUSH_DURATION_S [s].
PUSH_INTO_HOLD_S, PUSH_DURATION_S = 0.2, 0.1
#: The loop runs on this long [s] after the result, to see where the robot comes to rest.
AFTER_S = 0.5
#: Sim time [s] a goal may take before the run gives up on it.
TIMEOUT_S = 30.0
#: Below this base height [m], at any time, the robot has fallen.
FALLEN_HEIGHT_M = 0.2
#: A foot carrying more than this [N] counts as loaded when judging "standing".
LOADED_N = 5.0

DIRECTIONS_DEG = tuple(range(0, 360, 45))
IMPULSES_NS = (2.0, 4.0, 6.0, 8.0, 10.0)
QUICK_DIRECTIONS_DEG = (90, 315)
QUICK_IMPULSES_NS = (4.0, 8.0)

MENAGERIE = Plant.preset("menagerie")


@dataclass(frozen=True)
class PlantCase:
    """One row of the plant table: a plant, and the sensors and delay between it and the loop."""

    name: str = "nominal"
    plant: Plant = field(default_factory=Plant)
    #: Control periods between a command and the drivers applying it.
    delay_ticks: int = 0
    #: Control period [s] (1 ms: 1 kHz; 2 ms: 500 Hz).
    control_period_s: float = 1e-3
    #: What the robot measures (a :class:`sim.sensors.SensorModel` or a preset's name).
    sensors: SensorModel | str = DEFAULT_SENSORS
    #: Where the controller's state comes from: ``estimate`` (default) or ``truth``.
    state: str = "estimate"
    #: Sensor faults, their times counted from the goal's start [s].
    sensor_faults: tuple[SensorFault, ...] = ()
    #: The state estimator (:data:`wbc.estimation.estimators.ESTIMATORS`), when estimating.
    estimator: str = DEFAULT_ESTIMATOR

    def sensor_model(self) -> SensorModel:
        """The sensor model (the preset resolved)."""
        return (SensorModel.preset(self.sensors) if isinstance(self.sensors, str)
                else self.sensors)


GO2_SENSORS = SensorModel.preset(DEFAULT_SENSORS)
PLANT_CASES = (
    PlantCase(),
    PlantCase("foot friction 0.5", MENAGERIE.with_params(foot_friction=0.5)),
    PlantCase("foot friction 0.35", MENAGERIE.with_params(foot_friction=0.35)),
    PlantCase("payload 1.5 kg", MENAGERIE.with_params(payload_kg=1.5)),
    PlantCase("payload 3 kg", MENAGERIE.with_params(payload_kg=3.0)),
    PlantCase("ideal plant", Plant.preset("ideal")),
    PlantCase("unitree-mujoco plant", Plant.preset("unitree-mujoco")),
    PlantCase("identified plant", Plant.preset("identified")),
    PlantCase("delay 1 tick", delay_ticks=1),
    PlantCase("delay 2 ticks", delay_ticks=2),
    PlantCase("delay 4 ticks", delay_ticks=4),
    PlantCase("joint noise 1e-3 rad, 0.05 rad/s", sensors=GO2_SENSORS.with_params(
        joint_position_noise_rad=1e-3, joint_velocity_noise_rad_s=0.05)),
    PlantCase("joint noise 5e-3 rad, 0.1 rad/s", sensors=GO2_SENSORS.with_params(
        joint_position_noise_rad=5e-3, joint_velocity_noise_rad_s=0.1)),
    PlantCase("all: friction 0.5, 1.5 kg, delay 2, noise 1e-3",
              MENAGERIE.with_params(foot_friction=0.5, payload_kg=1.5), delay_ticks=2,
              sensors=GO2_SENSORS.with_params(joint_position_noise_rad=1e-3)),
)
QUICK_PLANT_CASES = (PLANT_CASES[1], PLANT_CASES[9])

#: Payload of the sweeps: 2 kg, 5 cm in front of the base's centre.
SWEEP_PAYLOAD = {"payload_kg": 2.0, "payload_offset_m": (0.05, 0.0, 0.0)}


def _sweep_case(base: Plant, label: str, payload: bool, **joints: float) -> PlantCase:
    changes = {**joints, **(SWEEP_PAYLOAD if payload else {})}
    return PlantCase(f"{label}{', 2 kg' if payload else ''}", base.with_params(**changes))


#: Joint friction the controller does not know, on Menagerie's contacts: damping
#: [N m s/rad] x friction loss [N m] (every joint) x payload.
JOINT_SWEEP = tuple(
    _sweep_case(MENAGERIE, f"damping {d:g}, friction loss {f:g}", p, joint_damping=d,
                joint_friction_loss=f)
    for p in (False, True) for d in (0.0, 0.5, 1.0, 2.0, 3.0) for f in (0.0, 0.2, 0.4))
#: The identified GO2's joints with more calf friction: calf friction loss [N m] x damping
#: [N m s/rad] (every joint) x payload.
CALF_SWEEP = tuple(
    _sweep_case(Plant.preset("identified"), f"calf friction {c:g}, damping {d:g}", p,
                calf_friction_loss=c, joint_damping=d)
    for p in (False, True) for c in (0.2, 0.5, 1.0, 1.4) for d in (0.1, 0.3, 2.0))
QUICK_JOINT_SWEEP = (JOINT_SWEEP[-1],)
QUICK_CALF_SWEEP = (CALF_SWEEP[-1],)
#: The sweeps' high five holds as long as the README's (2 s).
SWEEP_HOLD_S = 2
#: Plants on which the default controller is compared with one told their joint friction.
COMPENSATION_CASES = (PlantCase("menagerie", MENAGERIE),
                      PlantCase("identified, calf friction 1.4",
                                Plant.preset("identified").with_params(calf_friction_loss=1.4)))


@dataclass
class Episode:
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


def make_loop(case: PlantCase = PlantCase(), *, seed: int = 0,
              controller: BalanceController | None = None,
              faults_from_s: float = SETTLE_S) -> ControlLoop:
    """A control loop on a fresh standing MuJoCo GO2 built with ``case``'s plant and sensors.

    ``seed`` seeds the sensors' noise and biases; the case's sensor faults start
    ``faults_from_s`` [s] later than their own times (a goal is sent at :data:`SETTLE_S`).
    """
    period = case.control_period_s
    return ControlLoop.simulated(
        plant=case.plant, control_period_s=period,
        controller=controller or WholeBodyController(control_period_s=period),
        sensors=case.sensor_model(), sensor_seed=seed, state=case.state,
        estimator=(make_estimator(case.estimator, control_period_s=period)
                   if case.state == "estimate" else None),
        command_delay_ticks=case.delay_ticks,
        sensor_faults=[replace(f, at_s=f.at_s + faults_from_s) for f in case.sensor_faults])


def run_high_five(case: PlantCase = PlantCase(), *, pushes: Sequence[Push] = (),
                  hold_s: int = HOLD_S, height_m: float = HEIGHT_M, seed: int = 0,
                  hooks: Sequence[TickHook] = (), after_s: float = AFTER_S,
                  measure: bool = True, controller: BalanceController | None = None) -> Episode:
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
    loop = make_loop(case, seed=seed, controller=controller)
    loop.spin_for(SETTLE_S)
    start = loop.sim.time_s
    phases: list[tuple[float, str]] = []
    metrics = MetricsHook(loop, lambda: phases[-1][1] if phases else "") if measure else None
    extremes = _Extremes()
    timed = [replace(push, at_s=start + push.at_s) for push in pushes]
    loop.hooks += [PushSchedule(loop.sim, timed), extremes, *hooks]
    if metrics is not None:
        loop.hooks.append(metrics)

    def on_feedback(message: Any) -> None:
        phase = message.feedback.phase
        if not phases or phases[-1][1] != phase:
            phases.append((round(loop.context.now_s - start, 4), phase))

    wall = time.perf_counter()
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=height_m, hold_seconds=hold_s), timeout=TIMEOUT_S,
        feedback_callback=on_feedback)
    loop.spin_for(after_s)
    summary = None if metrics is None else metrics.metrics.summary(time.perf_counter() - wall)
    final, _ = loop.true_state()
    return Episode(
        status=result.status, message=result.result.message,
        min_height_m=extremes.min_height_m, final_height_m=float(final[2]),
        max_tilt_deg=extremes.max_tilt_deg, final_tilt_deg=tilt_deg(final),
        standing=standing_on_four_feet(loop), summary=summary, start_s=start, phases=phases,
        loop=loop)


def hold_push(direction_deg: float, impulse_ns: float, *, body: str = "base",
              duration_s: float = PUSH_DURATION_S, into_hold_s: float = PUSH_INTO_HOLD_S) -> Push:
    """A horizontal push of ``impulse_ns`` [N s] over ``duration_s`` [s], during the hold."""
    return Push(at_s=HOLD_START_S + into_hold_s, force_n=impulse_ns / duration_s,
                duration_s=duration_s, direction_deg=direction_deg, body=body)


def run_episode(case: PlantCase = PlantCase(), *, push: Push | None = None,
                hold_s: int = HOLD_S, height_m: float = HEIGHT_M, seed: int = 0,
                measure: bool = True, gains: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """One high five as a JSON-ready row (:meth:`Episode.row`): what every table and sweep runs.

    Args:
        case: The plant, sensor noise, delay and control period.
        push: A push whose ``at_s`` counts from the goal's start [s] (see :func:`hold_push`).
        hold_s: The goal's hold [s]. height_m: Its foot height [m].
        seed: Seed of the sensors' noise and biases.
        measure: Add the tracking, sliding and QP-failure metrics to the row.
        gains: :class:`wbc.ControllerConfig` fields for the controller (checked there); the
            default controller when empty.
    """
    controller = None
    if gains:
        controller = WholeBodyController(control_period_s=case.control_period_s, **gains)
    episode = run_high_five(case, pushes=() if push is None else (push,), hold_s=hold_s,
                            height_m=height_m, seed=seed, measure=measure, controller=controller)
    return episode.row()


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


def _yes(flag: bool) -> str:
    return "yes" if flag else "no"


def push_grid_lines(directions: Sequence[str], impulses: Sequence[str],
                    cell: Callable[[str, str], str]) -> list[str]:
    """The push grid as text: a row per impulse, a column per direction, each cell
    ``cell(impulse, direction)`` (columns at least 4 characters wide)."""
    width = max(4, *(len(cell(i, d)) for i in impulses for d in directions)) + 1
    lines = ["impulse [N s] | direction [deg]",
             "              |" + "".join(f"{d:>{width}}" for d in directions)]
    for impulse in impulses:
        lines.append(f"{impulse:>13} |" + "".join(
            f"{cell(impulse, d):>{width}}" for d in directions))
    return lines


def format_report(report: dict[str, Any]) -> str:
    """The two tables as text."""
    grid = report["push_grid"]
    title = (f"Pushes on the base during the hold ({grid['duration_s']:g} s, starting "
             f"{grid['starts_into_hold_s']:g} s into a {report['goal']['hold_s']} s hold of a "
             f"{report['goal']['target_height_m']:.2f} m high five)")
    outcome = {(f"{c['impulse_ns']:g}", str(c["direction_deg"])): c["outcome"]
               for c in grid["cells"]}
    lines = [(f"State: estimated ({DEFAULT_ESTIMATOR}) from the {DEFAULT_SENSORS} sensors unless "
              "a row says otherwise; everything measured on the simulator's truth"), "",
             title, "S succeeded, A aborted (foot put down, robot up), F fell", "",
             *push_grid_lines([str(d) for d in grid["directions_deg"]],
                              [f"{i:g}" for i in grid["impulses_ns"]],
                              lambda impulse, direction: outcome[impulse, direction])]
    total = len(grid["cells"])
    lines += ["", f"succeeded {grid['succeeded']}/{total} ({100 * grid['success_rate']:.0f} %), "
              f"aborted {grid['aborted']}, fell {grid['fell']}; any fall: "
              f"{_yes(grid['any_fall'])}" + "".join(
                  f"; fell at {c['impulse_ns']:g} N s toward {c['direction_deg']} deg"
                  for c in grid["cells"] if c["outcome"] == "F"), "",
              "Plant changes (no push)", ""]
    header = (f"{'plant change':<66} {'result':<9} {'track RMS':>9} {'hold RMS':>8} "
              f"{'sliding':>7} {'min z':>5} {'tilt':>5} {'end tilt':>8} {'QP fail':>7} "
              f"{'standing':>8} {'fell':>4}")
    units = (f"{'':<66} {'':<9} {'[mm]':>9} {'[mm]':>8} {'[mm]':>7} {'[m]':>5} {'[deg]':>5} "
             f"{'[deg]':>8}")
    lines += [header, units]
    for row in report["plant_changes"]:
        lines.append(f"{row['name']:<66} {row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                     f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                     f"{row['min_height_m']:>5.3f} {row['max_tilt_deg']:>5.1f} "
                     f"{row['final_tilt_deg']:>8.1f} {row['qp_failures']:>7} "
                     f"{_yes(row['standing']):>8} {_yes(row['fell']):>4}")
    for key, title in (("joint_sweep", "Joint friction sweep (Menagerie contacts)"),
                       ("calf_sweep", "Calf friction sweep (identified joints)")):
        sweep = report[key]
        lines += ["", f"{title}, {SWEEP_HOLD_S} s hold, {sweep['wall_s']:g} s wall", "",
                  (f"{'plant':<40} {'result':<9} {'track RMS':>9} {'hold RMS':>8} "
                   f"{'sliding':>7} {'tilt':>5} {'end tilt':>8} {'QP fail':>7}")]
        for row in sweep["rows"]:
            lines.append(f"{row['name']:<40} {row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                         f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                         f"{row['max_tilt_deg']:>5.2f} {row['final_tilt_deg']:>8.2f} "
                         f"{row['qp_failures']:>7}")
        lines.append(f"succeeded {sweep['succeeded']}/{len(sweep['rows'])}, max tilt "
                     f"{sweep['max_tilt_deg']:.2f} deg, worst end tilt "
                     f"{sweep['max_final_tilt_deg']:.2f} deg")
    if "compensation" in report:
        lines += ["", "Known joint friction fed forward (known_joint_damping/_friction)", "",
                  (f"{'plant':<32} {'friction':<8} {'result':<9} {'track RMS':>9} "
                   f"{'hold RMS':>8} {'sliding':>7} {'tilt':>5} {'end tilt':>8}")]
        for row in report["compensation"]["rows"]:
            lines.append(f"{row['name']:<32} {'known' if row['known_friction'] else 'unknown':<8} "
                         f"{row['status']:<9} {row['tracking_rms_mm']:>9.2f} "
                         f"{row['holding_rms_mm']:>8.2f} {row['stance_sliding_max_mm']:>7.2f} "
                         f"{row['max_tilt_deg']:>5.2f} {row['final_tilt_deg']:>8.2f}")
    return "\n".join(lines)


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
    started = time.perf_counter()
    report = run(quick=args.quick, jobs=args.jobs, log=lambda msg: print(
        f"[{time.perf_counter() - started:6.1f} s] {msg}", file=sys.stderr, flush=True))
    report["benchmark_wall_s"] = round(time.perf_counter() - started, 1)
    print(format_report(report))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=1, allow_nan=False))
    print(f"\nWrote {args.json} in {report['benchmark_wall_s']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
