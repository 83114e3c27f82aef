"""The sensors calibrated on the robot, and the IMU biases' effect, over several sensor seeds.

Run ``python -m benchmarks.sensor_calibration [--quick] [--json PATH] [--jobs N]``.

Every run is a :class:`sim.episode.Episode` (the default plant, controller and high five:
0.40 m, hold 2 s) run by :class:`sim.episode_runner.EpisodeRunner`, measured on the
simulator's truth, for sensor seeds 0-4:

1. Foot counts on another scale, 30 + 0.25 count/N (``--set sensors.foot_force_offset=30
   --set sensors.foot_force_gain=0.25``), unknown to the estimator (its default calibration
   is 10 + 2.5/N): with a 2 s standing calibration (``calibrate_s=2``), the learnt gains'
   and offsets' largest errors and the high five; without it, the estimator's fault and the
   high five.
2. The IMU at rest: what the standing calibration reads (gyroscope bias, gravity, the
   accelerometer's bias against the feet's plane) against the simulated sensors' true
   biases, with five times the preset's accelerometer bias (0.1 m/s^2).
3. The IMU biases in closed loop: the preset's, accelerometer bias x5 (0.1 m/s^2) with the
   gyroscope's x5 (1e-3 rad/s), and accelerometer x5 with gyroscope x25 (5e-3 rad/s: what
   ``docs/state-estimation.md`` once called "five times"), on each estimator, and the x5
   case again on the invariant EKF after a 2 s standing calibration (which gives it the
   accelerometer bias and the tilt measured against the feet): raised foot RMS, largest
   true tilt, the estimate's largest roll and pitch errors (the calibration's circle
   included); the worst seed.

``--quick`` runs seeds 0 and 2 only.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.reporting import json_safe, machine
from benchmarks.robustness import process_pool
from sim.episode import Episode
from sim.episode_runner import EpisodeRunner
from wbc.estimation.foot_force_calibration import FootForceCalibration

SEEDS, QUICK_SEEDS = (0, 1, 2, 3, 4), (0, 2)
#: The foot sensors of table 1 and their true calibration.
RESCALED = (("foot_force_offset", 30.0), ("foot_force_gain", 0.25))
RESCALED_TRUTH = FootForceCalibration(offset=30.0, gain=0.25)
#: Table 3's IMU cases: (name, sensor parameters).
IMU_CASES = (
    ("preset biases", ()),
    ("accel x5, gyro x5", (("accel_bias_m_s2", 0.1), ("gyro_bias_rad_s", 1e-3))),
    ("accel x5, gyro x25", (("accel_bias_m_s2", 0.1), ("gyro_bias_rad_s", 5e-3))),
)
ESTIMATORS = ("inekf", "kf")
#: The case run again after a 2 s standing calibration (the invariant EKF takes the bias and
#: the tilt measured against the feet: :meth:`wbc.InvariantEkf.set_imu_at_rest`).
CALIBRATED_CASE = "accel x5, gyro x5"
CALIBRATE_S = 2.0


def _outcome(result: Any) -> dict[str, Any]:
    s = result.metrics
    return {"status": result.status, "raised_foot_rms_mm": round(s.raised_foot_rms_mm, 2),
            "holding_rms_mm": round(s.holding_rms_mm, 2),
            "max_tilt_deg": round(s.max_base_tilt_deg, 2),
            "estimate_roll_max_deg": round(s.estimate_roll_max_deg, 3),
            "estimate_pitch_max_deg": round(s.estimate_pitch_max_deg, 3)}


def rescaled_row(job: tuple[int, bool]) -> dict[str, Any]:
    """Table 1: one seed, with or without the standing calibration."""
    seed, calibrate = job
    episode = Episode(sensor_params=RESCALED, sensor_seed=seed,
                      calibrate_s=CALIBRATE_S if calibrate else 0.0)
    faults: set[str] = set()

    def watch(loop: Any, out: Any) -> None:
        if loop.estimator.weight_contradicted:
            faults.add("FOOT_WEIGHT")

    result = EpisodeRunner(episode, metrics=True, hooks=[watch]).run()
    row = {"seed": seed, "calibrated": calibrate, **_outcome(result),
           "fault": ", ".join(sorted(faults)) or "none",
           "final_height_m": round(float(result.loop.true_state()[0][2]), 3)}
    if calibrate:
        report = result.calibration
        gain, offset_n = report.feet.errors_against(RESCALED_TRUTH)
        row.update(learnt=report.learnt, gain_error_pct=round(100 * gain, 2),
                   offset_error_counts=round(offset_n * 0.25, 2),
                   gains=[round(g, 4) for g in report.feet.gain],
                   offsets=[round(o, 2) for o in report.feet.offset])
    return row


def imu_at_rest_row(seed: int) -> dict[str, Any]:
    """Table 2: the standing calibration's IMU against the sensors' true biases."""
    episode = Episode(action=None, sensor_params=(("accel_bias_m_s2", 0.1),), sensor_seed=seed,
                      calibrate_s=CALIBRATE_S)
    result = EpisodeRunner(episode).run()
    sensors = result.loop.robot.robot.sensors
    imu = result.calibration.imu
    true_tilt = float(np.degrees(np.arctan2(np.hypot(*sensors.accel_bias[:2]), 9.81)))
    return {"seed": seed,
            "gyro_bias_error_rad_s": round(float(np.max(np.abs(
                imu.gyro_bias_rad_s - sensors.gyro_bias))), 5),
            "gravity_m_s2": round(imu.gravity_m_s2, 4),
            "true_accel_bias_m_s2": [round(float(b), 4) for b in sensors.accel_bias],
            "measured_accel_bias_m_s2": [round(float(b), 4) for b in imu.accel_bias_m_s2],
            "horizontal_error_m_s2": round(float(np.hypot(*(
                imu.accel_bias_m_s2[:2] - sensors.accel_bias[:2]))), 4),
            "true_bias_tilt_deg": round(true_tilt, 3),
            "measured_bias_tilt_deg": round(imu.tilt_from_bias_deg, 3)}


def imu_row(job: tuple[str, str, int, bool]) -> dict[str, Any]:
    """Table 3: one IMU case, estimator and seed, with or without the calibration."""
    name, estimator, seed, calibrate = job
    params = dict(IMU_CASES)[name]
    episode = Episode(sensor_params=params, sensor_seed=seed, estimator=estimator,
                      calibrate_s=CALIBRATE_S if calibrate else 0.0)
    result = EpisodeRunner(episode, metrics=True).run()
    if calibrate:
        name += ", 2 s calibration"
    return {"case": name, "estimator": estimator, "seed": seed, **_outcome(result)}


def run(*, quick: bool = False, jobs: int | None = None) -> dict[str, Any]:
    """Every table; the report as a dict."""
    seeds = QUICK_SEEDS if quick else SEEDS
    started = time.perf_counter()
    with process_pool(jobs, preload=["sim.episode_runner"]) as pool:
        rescaled = list(pool.map(rescaled_row, [(s, c) for c in (True, False) for s in seeds]))
        at_rest = list(pool.map(imu_at_rest_row, seeds))
        imu = list(pool.map(imu_row, [(name, est, s, False) for name, _ in IMU_CASES
                                      for est in ESTIMATORS for s in seeds]
                            + [(CALIBRATED_CASE, "inekf", s, True) for s in seeds]))
    worst = []
    pairs = list(dict.fromkeys((r["case"], r["estimator"]) for r in imu))  # in run order
    for name, est in pairs:
        rows = [r for r in imu if r["case"] == name and r["estimator"] == est]
        bad = max(rows, key=lambda r: r["raised_foot_rms_mm"])
        worst.append({"case": name, "estimator": est, "worst_seed": bad["seed"],
                      "raised_foot_rms_mm": bad["raised_foot_rms_mm"],
                      "max_tilt_deg": max(r["max_tilt_deg"] for r in rows),
                      "estimate_tilt_error_max_deg": max(
                          max(r["estimate_roll_max_deg"], r["estimate_pitch_max_deg"])
                          for r in rows),
                      "statuses": "/".join(sorted({r["status"] for r in rows}))})
    return {"machine": machine(), "seeds": list(seeds), "rescaled_feet": rescaled,
            "imu_at_rest": at_rest, "imu_biases": imu, "imu_worst": worst,
            "wall_s": round(time.perf_counter() - started, 1)}


def format_report(report: dict[str, Any]) -> str:
    """The tables as Markdown."""
    lines = ["Foot counts 30 + 0.25/N (the estimator's default: 10 + 2.5/N)", "",
             ("| seed | calibration | gain error max [%] | offset error max [counts] | "
              "result | raised foot RMS [mm] | max tilt [deg] | fault | final height [m] |"),
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in report["rescaled_feet"]:
        learnt = "2 s standing" if r["calibrated"] else "off"
        gain = f"{r['gain_error_pct']:.1f}" if r["calibrated"] else "-"
        offset = f"{r['offset_error_counts']:.2f}" if r["calibrated"] else "-"
        lines.append(f"| {r['seed']} | {learnt} | {gain} | {offset} | {r['status']} | "
                     f"{r['raised_foot_rms_mm']:.2f} | {r['max_tilt_deg']:.2f} | {r['fault']} | "
                     f"{r['final_height_m']:.3f} |")
    lines += ["", "The IMU at rest (accelerometer bias 0.1 m/s^2, 2 s standing calibration)", "",
              ("| seed | gyro bias error max [rad/s] | gravity [m/s^2] | horizontal accel bias "
               "true / measured [deg of tilt] | its error [m/s^2] |"),
              "| --- | --- | --- | --- | --- |"]
    for r in report["imu_at_rest"]:
        lines.append(f"| {r['seed']} | {r['gyro_bias_error_rad_s']:.5f} | {r['gravity_m_s2']:.3f} "
                     f"| {r['true_bias_tilt_deg']:.3f} / {r['measured_bias_tilt_deg']:.3f} | "
                     f"{r['horizontal_error_m_s2']:.4f} |")
    lines += ["", "IMU biases in closed loop (high five), worst of the seeds", "",
              ("| case | estimator | results | worst seed | raised foot RMS there [mm] | "
               "max tilt [deg] | estimate's tilt error max [deg] |"),
              "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in report["imu_worst"]:
        lines.append(f"| {r['case']} | {r['estimator']} | {r['statuses']} | {r['worst_seed']} | "
                     f"{r['raised_foot_rms_mm']:.2f} | {r['max_tilt_deg']:.2f} | "
                     f"{r['estimate_tilt_error_max_deg']:.3f} |")
    lines.append(f"\n{report['wall_s']:g} s wall")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.sensor_calibration",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="seeds 0 and 2 only")
    parser.add_argument("--json", type=Path, default=Path("out/sensor_calibration.json"),
                        help="where the report goes (default: out/sensor_calibration.json)")
    parser.add_argument("--jobs", type=int, default=None,
                        help="worker processes (default: every core)")
    args = parser.parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        parser.error(f"--jobs: expected a whole number >= 1, received {args.jobs}")
    report = run(quick=args.quick, jobs=args.jobs)
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(json_safe(report), indent=2) + "\n", encoding="utf-8")
    print(format_report(report))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
