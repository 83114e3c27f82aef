"""``go2-wbc run --dds`` against the project's test peers of Unitree's simulators
(``go2-wbc bridge --framing unitree-python|unitree-cpp``), with the default settings: the robot
starts lying (no torque until the first command, as Unitree's), the controller stands it up
(a ``stand`` goal), then a high five (0.40 m held 2 s), then Ctrl-C: the controller's stop
sits the robot down (a ``sit`` goal); each must SUCCEED.

Judged against the bridge's truth (``--log``): the raised foot's height (its centre, world
frame), the longest time it stayed within 1 cm of its peak, the base's largest tilt. With
``unitree-cpp`` the states carry a tick (the simulated milliseconds), so the controller's tick
log joins the truth (:func:`sim.dds_evaluation.goal_runs`: raised foot against its target);
Unitree's Python simulator sends tick 0, so there only the truth's own figures are given.

Run ``python -m benchmarks.unitree_peers --runs 5`` (about 40 s a run); the tests run one.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from tempfile import TemporaryDirectory
from typing import Any

import numpy as np

from benchmarks.dds_outputs import ControllerFigures, TruthMonitor, client_outcome, standing
from benchmarks.dds_processes import DdsProcesses, private_domain_id
from sim.dds_evaluation import goal_runs
from sim.state_framing import UNITREE_CPP, UNITREE_PYTHON, UNITREE_PYTHON_RATE_HZ

#: The peers, with their state rates [Hz].
PEERS = {UNITREE_PYTHON: int(UNITREE_PYTHON_RATE_HZ), UNITREE_CPP: 500}
#: Longest waits [s, wall]: the stand-up from lying, a goal.
STAND_TIMEOUT_S, GOAL_TIMEOUT_S = 20.0, 40.0
_FR = 1  # the raised foot's index in the truth's legs (FL, FR, RL, RR)


@dataclass
class PeerRun:
    """One run's outcome and figures."""

    framing: str
    #: The controller's lines up to "controlling at" (what it recognised, its limits).
    start_lines: list[str]
    #: The goals' ends in the controller's report, in order ('succeeded', ...): stand,
    #: high five, sit (and a recovery stand after each fallback, if any).
    goal_events: list[str]
    #: The high five client's final status, the controller's stop notes.
    high_five: str
    stop_notes: list[str]
    #: The truth: the FR foot's peak height [m], how long it stayed within 1 cm of it [s],
    #: the base's largest tilt [deg] while the foot was up (> 5 cm) and over the whole run
    #: (the stand-up from lying included).
    foot_peak_m: float
    foot_hold_s: float
    tilt_max_deg: float
    tilt_run_max_deg: float
    #: The controller's staleness limit [s] and its watchdog trips.
    stale_after_s: float
    watchdog_trips: int
    #: The controller's robot counters (``stream``: kind, rate, repeats, ...).
    robot: dict[str, Any]
    #: :func:`sim.dds_evaluation.goal_runs`' high five figures (``unitree-cpp`` only).
    joined: dict[str, Any] = field(default_factory=dict)

    @property
    def succeeded(self) -> bool:
        """Stand, high five and sit all SUCCEEDED (and any recovery stand: no goal ended
        otherwise)."""
        return (len(self.goal_events) >= 3 and set(self.goal_events) == {"succeeded"}
                and self.high_five == "SUCCEEDED")

    def line(self) -> str:
        """One line of figures."""
        joined = ""
        if self.joined:
            joined = (f", raised foot vs target RMS {self.joined['raised_foot_rms_mm']:.2f} mm "
                      f"(max {self.joined['raised_foot_max_mm']:.1f} mm)")
        stream = self.robot.get("stream", {})
        return (f"{self.framing}: {'SUCCEEDED' if self.succeeded else 'FAILED'} "
                f"(goals {self.goal_events}, high five {self.high_five}, stop "
                f"{self.stop_notes}); FR "
                f"foot peak {self.foot_peak_m:.3f} m held {self.foot_hold_s:.2f} s{joined}; tilt "
                f"max {self.tilt_max_deg:.2f} deg with the foot up, {self.tilt_run_max_deg:.2f} "
                f"deg over the run; limit {self.stale_after_s * 1e3:.0f} ms, "
                f"watchdog trips {self.watchdog_trips}; states used "
                f"{self.robot.get('states_used')}, repeats {stream.get('repeats')}, dropped "
                f"{stream.get('dropped')}")


def tilt_deg(q: np.ndarray) -> np.ndarray:
    """The base's tilt [deg] (its z axis from the vertical) of truth ``q`` rows (Pinocchio's
    quaternion ``(x, y, z, w)`` at 3:7)."""
    x, y = q[:, 3], q[:, 4]
    return np.degrees(np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)))


def truth_figures(truth: dict[str, np.ndarray]) -> tuple[float, float, float, float]:
    """The FR foot's peak height [m] and time within 1 cm of it [s] once the robot first
    stood (feet loaded, base up), the largest tilt [deg] while that foot was more than 5 cm
    up, and over the whole run."""
    feet = truth["foot_force_n"]
    up = np.flatnonzero((feet.min(axis=1) >= 20.0) & (truth["q"][:, 2] >= 0.25))
    start = int(up[0]) if up.size else 0
    height = truth["foot_position_m"][start:, _FR, 2]
    t_s = truth["t_s"][start:]
    peak = float(height.max()) if height.size else math.nan
    near = height >= peak - 0.01
    hold = 0.0
    if near.any():  # the longest run of samples near the peak
        edges = np.flatnonzero(np.diff(np.concatenate(([0], near.astype(int), [0]))))
        hold = max(float(t_s[b - 1] - t_s[a]) for a, b in zip(edges[::2], edges[1::2],
                                                              strict=True))
    tilt = tilt_deg(truth["q"][start:])
    raised = tilt[height > 0.05]
    return (peak, hold, float(raised.max()) if raised.size else math.nan,
            float(tilt_deg(truth["q"]).max()))


def run_peer(framing: str, workdir: Path, *, domain_offset: int = 2,
             controller_args: tuple[str, ...] = ()) -> PeerRun:
    """One run against the peer ``framing`` (see the module doc), the controller with
    ``controller_args`` added to the defaults; processes are stopped whatever happens."""
    with DdsProcesses(workdir, domain_id=private_domain_id(domain_offset)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        bridge = run.bridge("--framing", framing, rate_hz=PEERS[framing])
        controller = run.controller(*controller_args)
        truth.wait_for(standing, timeout_s=STAND_TIMEOUT_S, hold_s=0.5,
                       what="the robot standing on four loaded feet")
        client = run.high_five(height_m=0.4, hold_s=2.0)
        client.wait(GOAL_TIMEOUT_S)
        high_five = client_outcome(client.output()).status
        controller.stop()  # Ctrl-C: the stop sits the robot down
        bridge.stop()
        text = controller.output()
        start = text[:text.find("controlling at")].splitlines()
        figures = ControllerFigures.read(controller.report_path)
        with np.load(bridge.log_path) as data:
            truth_log = {name: data[name] for name in data.files}
        peak, hold, tilt, tilt_run = truth_figures(truth_log)
        joined: dict[str, Any] = {}
        if framing == UNITREE_CPP:
            fives = [r for r in goal_runs(controller.log_path, truth_log)
                     if r.action == "high_five"]
            joined = fives[0].as_dict() if fives else {}
        return PeerRun(
            framing=framing, start_lines=start,
            goal_events=[g["event"] for g in figures.goals], high_five=high_five or "",
            stop_notes=figures.stop_notes, foot_peak_m=peak, foot_hold_s=hold, tilt_max_deg=tilt,
            tilt_run_max_deg=tilt_run,
            stale_after_s=figures.stale_after_s, watchdog_trips=figures.watchdog_trips,
            robot=figures.robot, joined=joined)


def main(argv: list[str] | None = None) -> int:
    """``python -m benchmarks.unitree_peers [--runs N] [--framing F ...]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1, help="runs per peer (default: 1)")
    parser.add_argument("--framing", choices=tuple(PEERS), action="append",
                        help="a peer (repeatable; default: both)")
    parser.add_argument("--stale-after", metavar="S",
                        help="the controller's --stale-after (default: its own, from the rate)")
    args = parser.parse_args(argv)
    failures = 0
    for framing in args.framing or tuple(PEERS):
        for k in range(args.runs):
            with TemporaryDirectory() as tmp:
                result = run_peer(framing, Path(tmp), controller_args=(
                    ("--stale-after", args.stale_after) if args.stale_after else ()))
            failures += not result.succeeded
            print(f"run {k + 1}/{args.runs} {result.line()}", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
