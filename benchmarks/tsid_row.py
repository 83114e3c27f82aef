"""An optional TSID row: TSID timed on the recorded states and references of the benchmark's
lift, in turns with the project's controller and PlaCo, in one run.

TSID cannot live in the project's environment (the registry has its bindings but only the
source of ``libtsid``, built against a newer Pinocchio than PlaCo's), so it runs in its own
(``make tsid`` builds ``.venv-tsid``; ``GO2_WBC_TSID_PYTHON`` names another interpreter) as a
subprocess, :mod:`benchmarks.tsid_peer`, fed one file: every tick's state and every reference
the project's controller held. The row is skipped, with the reason, when no such interpreter
is found.

Run alone: ``python -m benchmarks.tsid_row [--quick]``. The project's modules are imported
where they are used, so that finding TSID (or not) costs no controller import.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from benchmarks.lift_timing import Recording
    from wbc.controller.balance_controller import BalanceController
    from wbc.motions.leg_lift import LegLiftTiming

TSID = "tsid"
ROOT = Path(__file__).resolve().parent.parent
#: Where ``make tsid`` puts TSID's environment.
TSID_VENV_PYTHON = ROOT / ".venv-tsid" / "bin" / "python"
PEER = Path(__file__).resolve().parent / "tsid_peer.py"


def tsid_python() -> tuple[str | None, str]:
    """The interpreter that has TSID, or None with the reason it is not there."""
    named = os.environ.get("GO2_WBC_TSID_PYTHON")
    python = Path(named) if named else TSID_VENV_PYTHON
    if not python.exists():
        return None, (f"no TSID environment ({python} does not exist; `make tsid` builds it, "
                      "or set GO2_WBC_TSID_PYTHON)")
    found = subprocess.run([str(python), "-c", "import tsid, pinocchio"],
                           capture_output=True, text=True, timeout=120)
    if found.returncode != 0:
        last = (found.stderr.strip().splitlines() or ["no output"])[-1]
        return None, f"{python} cannot import tsid: {last}"
    return str(python), ""


class _ReferenceLog:
    """A controller that records the references the lift gives it, then passes them on."""

    def __init__(self, controller: Any, legs: list[str]):
        self._controller = controller
        self.com = [np.zeros(3)] * 3
        self.feet = {leg: [np.zeros(3)] * 3 for leg in legs}

    def __getattr__(self, name: str) -> Any:
        return getattr(self._controller, name)

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        self._controller.set_com_target(position, velocity, acceleration)
        self.com = [np.array(x if x is not None else np.zeros(3), float)
                    for x in (position, velocity, acceleration)]

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        self._controller.set_foot_target(leg, position, velocity, acceleration,
                                         clamp_to_reach=clamp_to_reach)
        self.feet[leg] = [self._controller.foot_target(leg), *(
            np.array(x if x is not None else np.zeros(3), float)
            for x in (velocity, acceleration))]


def tsid_problem(recording: Recording, *, hold_s: float, timing: LegLiftTiming | None
                 ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The file TSID's peer reads (the recorded states and, tick by tick, the references
    the project's controller held), and the project's own torques and phases on it."""
    import pinocchio as pin

    from benchmarks.lift_timing import HEIGHT_M, LEG
    from wbc.controller.whole_body_controller import WholeBodyController
    from wbc.model.description import FOOT_FRAMES, JOINT_NAMES, LEGS
    from wbc.motions.leg_lift import LegLift

    controller = WholeBodyController()
    log = _ReferenceLog(controller, list(LEGS))
    controller.reset(recording.q[0])
    log.com = [controller.com_target, np.zeros(3), np.zeros(3)]
    lift = LegLift(log, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s,  # type: ignore[arg-type]
                   timing=timing)
    lift.start(float(recording.t[0]))
    cfg, description = controller.config, controller.description
    yaw = pin.rpy.matrixToRpy(pin.Quaternion(recording.q[0][3:7]).toRotationMatrix())[2]
    ticks, n_legs = len(recording.t), len(LEGS)
    rows: dict[str, list[Any]] = {key: [] for key in (
        "com_p", "com_v", "com_a", "foot_p", "foot_v", "foot_a", "force_bounds", "stance",
        "foot_weight", "tau", "phase")}
    bounds = np.zeros(n_legs)
    for q, v, t in zip(recording.q, recording.v, recording.t):
        lift.advance(float(t))
        out = controller.step(q, v)
        rows["tau"].append(out.tau_ff)
        rows["phase"].append(str(lift.phase))
        for key, value in zip(("com_p", "com_v", "com_a"), log.com):
            rows[key].append(value)
        for i, key in enumerate(("foot_p", "foot_v", "foot_a")):
            rows[key].append([log.feet[leg][i] for leg in LEGS])
        rows["force_bounds"].append(controller.schedule.normal_force_bounds(bounds).copy())
        rows["stance"].append([controller.schedule.is_stance(leg) for leg in LEGS])
        rows["foot_weight"].append([cfg.weights.foot_weight] * n_legs)
    posture = controller.posture_target
    problem = {
        "urdf": np.array(str(description.urdf_path)),
        "package_dir": np.array(str(description.package_share_dir)),
        "joint_names": np.array(JOINT_NAMES), "foot_frames": np.array(
            [FOOT_FRAMES[leg] for leg in LEGS]),
        "q": recording.q, "v": recording.v, "t": recording.t - recording.t[0],
        "tau_max": cfg.limits.torque_limit_fraction * description.effort_limit,
        "base_rotation": np.repeat(pin.rpy.rpyToMatrix(0.0, 0.0, yaw)[None], ticks, axis=0),
        "posture_p": np.repeat(posture[None], ticks, axis=0),
        "posture_v": np.zeros((ticks, len(JOINT_NAMES))),
        "posture_a": np.zeros((ticks, len(JOINT_NAMES))),
        **{key: np.array(rows[key], float) for key in (
            "com_p", "com_v", "com_a", "foot_p", "foot_v", "foot_a", "force_bounds",
            "foot_weight")},
        "stance": np.array(rows["stance"], bool),
        **{name: np.array(float(getattr(part, name))) for part in (
            cfg.gains, cfg.weights, cfg.contacts) for name in (
            "com_kp", "base_orientation_kp", "posture_kp", "foot_kp", "contact_damping",
            "com_weight", "base_orientation_weight", "posture_weight", "force_weight",
            "friction_coefficient", "min_normal_force_n", "max_normal_force_n")
            if hasattr(part, name)},
    }
    ours = {"tau": np.array(rows["tau"], float), "phase": np.array(rows["phase"])}
    return problem, ours


def run_peer(python: str, problem: dict[str, np.ndarray]) -> dict[str, Any]:
    """TSID's peer on the problem, in its own process: its per-tick seconds and torques."""
    with tempfile.TemporaryDirectory() as folder:
        problem_path, result_path = Path(folder, "problem.npz"), Path(folder, "result.json")
        np.savez(problem_path, **problem)
        done = subprocess.run([python, str(PEER), str(problem_path), str(result_path)],
                              capture_output=True, text=True, timeout=600)
        if done.returncode != 0:
            tail = "\n".join(done.stderr.strip().splitlines()[-5:])
            raise RuntimeError(f"TSID's peer failed (exit {done.returncode}): {tail}")
        return json.loads(result_path.read_text())


def _replay_times(recording: Recording, factory: Callable[[], BalanceController], *,
                  hold_s: float, timing: LegLiftTiming | None) -> np.ndarray:
    from benchmarks.lift_timing import HEIGHT_M, LEG
    from wbc.motions.leg_lift import LegLift

    controller = factory()
    controller.reset(recording.q[0])
    lift = LegLift(controller, leg=LEG, height_m=HEIGHT_M, hold_s=hold_s, timing=timing)
    lift.start(float(recording.t[0]))
    seconds = np.empty(len(recording.t))
    for k, (q, v, t) in enumerate(zip(recording.q, recording.v, recording.t)):
        lift.advance(float(t))
        start = time.perf_counter()
        controller.step(q, v)
        seconds[k] = time.perf_counter() - start
    return seconds


def run_tsid_row(*, hold_s: float, timing: LegLiftTiming | None, turns: int = 2
                 ) -> dict[str, Any]:
    """TSID, the default controller and PlaCo on the same recorded lift, in ``turns``
    alternations; per case (every tick; four feet before the lift; three feet with FR held
    up) the median of each controller's per-turn medians."""
    from benchmarks.lift_timing import DEFAULT, LEG, PLACO, record_lift, stats_us
    from wbc.controller.placo_controller import PlacoController
    from wbc.controller.whole_body_controller import WholeBodyController
    from wbc.model.description import LEGS

    python, reason = tsid_python()
    if python is None:
        return {"skipped": reason}
    recording = record_lift(hold_s=hold_s, timing=timing)
    problem, ours = tsid_problem(recording, hold_s=hold_s, timing=timing)
    stance = problem["stance"]
    cases = {"all ticks": np.ones(len(stance), bool),
             "four feet": stance.all(axis=1) & (ours["phase"] == "shifting"),
             "three feet + FR held": ~stance[:, LEGS.index(LEG)] & (ours["phase"] == "holding")}
    turns_s: dict[str, list[np.ndarray]] = {DEFAULT: [], PLACO: [], TSID: []}
    result: dict[str, Any] = {}
    for _ in range(turns):
        turns_s[DEFAULT].append(_replay_times(recording, WholeBodyController, hold_s=hold_s,
                                              timing=timing))
        result = run_peer(python, problem)
        turns_s[TSID].append(np.array(result["seconds"]))
        turns_s[PLACO].append(_replay_times(recording, PlacoController, hold_s=hold_s,
                                            timing=timing))
    table = {name: {case: {**stats_us(np.concatenate([s[mask] for s in samples])),
                           "turn_medians_us": [1e6 * float(np.median(s[mask]))
                                               for s in samples],
                           "ticks": int(mask.sum())}
                    for case, mask in cases.items()}
             for name, samples in turns_s.items()}
    tau = np.array(result["torques"])
    valid = np.isfinite(tau).all(axis=1)
    weight_n = float(WholeBodyController().description.total_mass * 9.81)
    return {"ticks": len(recording.t), "turns": turns, "table": table,
            "tsid_version": result["tsid_version"],
            "tsid_pinocchio_version": result["pinocchio_version"],
            "tsid_failed_ticks": int((~valid).sum()),
            "torque_difference_rms_nm": float(np.sqrt(np.mean(
                (tau[valid] - ours["tau"][valid]) ** 2))),
            "tsid_normal_force_over_weight_median": float(np.median(
                np.array(result["normal_force_n"])[valid]) / weight_n)}


def format_tsid_row(report: dict[str, Any]) -> str:
    """The table: per case, each controller's median (per-turn medians) and its ratio."""
    if "skipped" in report:
        return f"TSID: skipped, {report['skipped']}"
    from benchmarks.lift_timing import DEFAULT, PLACO

    table = report["table"]
    head = (f"TSID {report['tsid_version']} (its Pinocchio {report['tsid_pinocchio_version']}),"
            f" the default controller and PlaCo on one recorded lift ({report['ticks']} ticks,"
            f" {report['turns']} turns each, in alternation): median tick [us]")
    columns = (f"{'case':24} {'ticks':>6} {'default':>9} {'TSID':>9} {'PlaCo':>9}"
               f" {'default/TSID':>13} {'TSID/PlaCo':>11} {'default/PlaCo':>14}")
    lines = [head, columns]
    for case in table[DEFAULT]:
        med = {name: table[name][case]["median"] for name in (DEFAULT, TSID, PLACO)}
        lines.append(f"{case:24} {table[DEFAULT][case]['ticks']:>6} {med[DEFAULT]:>9.1f}"
                     f" {med[TSID]:>9.1f} {med[PLACO]:>9.1f} {med[DEFAULT] / med[TSID]:>13.2f}"
                     f" {med[TSID] / med[PLACO]:>11.2f} {med[DEFAULT] / med[PLACO]:>14.2f}")
    lines.append(f"TSID's torques against the default controller's:"
                 f" {report['torque_difference_rms_nm']:.2f} N m RMS (different formulations:"
                 f" a full 30-variable QP with linearised cones); its normal forces sum to"
                 f" {report['tsid_normal_force_over_weight_median']:.3f} of the robot's weight"
                 f" (median); failed ticks {report['tsid_failed_ticks']}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a short hold (0.3 s)")
    parser.add_argument("--turns", type=int, default=2, help="alternations (default 2)")
    args = parser.parse_args(argv)
    from benchmarks.lift_timing import HOLD_S, QUICK_HOLD_S, QUICK_TIMING

    report = run_tsid_row(hold_s=QUICK_HOLD_S if args.quick else HOLD_S,
                          timing=QUICK_TIMING if args.quick else None, turns=args.turns)
    print(format_tsid_row(report))
    return 0


if __name__ == "__main__":
    sys.exit(main())
