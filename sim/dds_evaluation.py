"""A goal run across processes, judged against the simulator's truth afterwards.

The controller process never sees the truth: ``go2-wbc run --dds --log`` records, per tick,
the ``LowState_.tick`` it answered, its estimate and its swing-foot targets
(:mod:`actions.robot.tick_log`); ``go2-wbc bridge --log`` records the simulator's exact
state with each ``LowState_.tick`` it published (:mod:`sim.truth_log`). Joined on that tick,
the two give the figures an in-process episode reports (:mod:`sim.episode_metrics`): the
raised foot against its target, the stance feet's travel, the base tilt, and the estimate
against the truth, the estimator's frame carried into the simulator's at goal start
(:class:`sim.episode_metrics.FrameAlignment`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sim.episode_metrics import EstimateErrors, FrameAlignment
from wbc.core.errors import ConfigurationError
from wbc.model.description import LEGS

#: A foot carrying less than this [N] at the end is not standing on the floor.
LOADED_FOOT_N = 5.0


@dataclass
class GoalRunMetrics:
    """One goal of a run across processes. Lengths [mm], angles [deg], forces [N]."""

    #: The goal's action, and its status at the last tick the controller logged it (the
    #: result itself is the client's).
    action: str
    last_logged_status: str
    #: Controller ticks of the goal joined with a truth sample, and the goal's span [s].
    ticks: int
    duration_s: float
    #: The raised foot against its target, over the ticks it was raised, and over the ticks
    #: its target stood still (the hold).
    raised_foot_rms_mm: float
    raised_foot_max_mm: float
    holding_rms_mm: float
    #: Largest horizontal travel of a stance foot's centre over the goal.
    stance_travel_max_mm: float
    #: Largest base tilt over the goal and the truth's foot forces at its last tick.
    max_tilt_deg: float
    final_foot_forces_n: list[float]
    #: The estimate against the truth (keys as :meth:`EstimateErrors.summary`).
    estimate: dict[str, float]

    @property
    def on_four_feet(self) -> bool:
        """Every foot carries at least :data:`LOADED_FOOT_N` at the goal's end."""
        return min(self.final_foot_forces_n) >= LOADED_FOOT_N

    def as_dict(self) -> dict[str, Any]:
        """The figures as plain values (JSON)."""
        return {**asdict(self), "on_four_feet": self.on_four_feet}


def _load(source: Path | str | dict[str, Any], what: str) -> dict[str, Any]:
    if isinstance(source, dict):
        return source
    try:
        with np.load(source) as data:
            return {name: data[name] for name in data.files}
    except (OSError, ValueError) as err:
        raise ConfigurationError(f"{what}: cannot read {str(source)!r} ({err})") from err


def _tilt_deg(quaternion_xyzw: np.ndarray) -> np.ndarray:
    """Angle [deg] between the base's z axis and the world's, per row of (n, 4) x, y, z, w."""
    x, y = quaternion_xyzw[:, 0], quaternion_xyzw[:, 1]
    cos_tilt = np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0)
    return np.degrees(np.arccos(cos_tilt))


def goal_runs(ticks: Path | str | dict[str, Any], truth: Path | str | dict[str, Any]
              ) -> list[GoalRunMetrics]:
    """The figures of every goal in a controller's tick log, against the bridge's truth log.

    Args:
        ticks: ``go2-wbc run --dds --log`` output (a path or its arrays).
        truth: ``go2-wbc bridge --log`` output of the same run (a path or its arrays).

    Raises:
        ConfigurationError: A log that cannot be read, or no tick of the controller's log
            found in the truth's (logs of different runs).
    """
    ticks = _load(ticks, "ticks")
    truth = _load(truth, "truth")
    row_of_tick = {int(tick): row for row, tick in enumerate(truth["tick"])}
    joined = np.array([row_of_tick.get(int(t), -1) for t in ticks["state_tick"]])
    usable = ticks["fresh"] & (joined >= 0)
    if len(ticks["state_tick"]) and not usable.any():
        raise ConfigurationError(
            "ticks: none of the controller's state ticks is in the truth log; give the "
            "logs of one run (the bridge's --log and the controller's --log)")
    statuses = [str(name) for name in ticks["goal_status_names"]]
    actions = [str(name) for name in ticks["action_names"]]
    goal = ticks["goal_action"]
    # A goal is a run of ticks with the same action index and a goal present.
    starts = np.flatnonzero((goal >= 0) & np.r_[True, goal[1:] != goal[:-1]])
    runs = []
    for start in starts:
        end = start
        while end + 1 < len(goal) and goal[end + 1] == goal[start]:
            end += 1
        rows = np.arange(start, end + 1)
        rows = rows[usable[rows]]
        if len(rows):
            runs.append(_goal_metrics(ticks, truth, rows, joined[rows],
                                      actions[goal[start]],
                                      statuses[int(ticks["goal_status"][end])]))
    return runs


def _goal_metrics(ticks: dict[str, Any], truth: dict[str, Any], rows: np.ndarray,
                  truth_rows: np.ndarray, action: str, last_status: str) -> GoalRunMetrics:
    q_est = ticks["q"][rows].astype(float)
    v_est = ticks["v"][rows].astype(float)
    q_true = truth["q"][truth_rows]
    v_true = truth["v"][truth_rows]
    alignment = FrameAlignment(q_est[0], q_true[0])
    errors = EstimateErrors(alignment)
    for k in range(len(rows)):
        errors.record(q_est[k], v_est[k], q_true[k], v_true[k])

    feet_true = truth["foot_position_m"][truth_rows]  # (n, 4, 3), world
    swing = ticks["swing"][rows]
    targets = ticks["foot_target"][rows].astype(float)
    raised: list[float] = []
    holding: list[float] = []
    for leg in range(len(LEGS)):
        up = np.flatnonzero(swing[:, leg] & np.isfinite(targets[:, leg, 0]))
        if not len(up):
            continue
        aligned = targets[up, leg] @ alignment.rotation.T + alignment.translation
        error_mm = 1e3 * np.linalg.norm(aligned - feet_true[up, leg], axis=1)
        raised.extend(error_mm)
        still = np.r_[False, np.all(np.abs(np.diff(targets[up, leg], axis=0)) < 1e-6, axis=1)]
        holding.extend(error_mm[still])
    stance = ~swing.any(axis=0)
    travel = np.linalg.norm(feet_true[:, stance, :2] - feet_true[0, stance, :2], axis=2)

    def rms(values: list[float]) -> float:
        return math.sqrt(float(np.mean(np.square(values)))) if values else 0.0

    return GoalRunMetrics(
        action=action, last_logged_status=last_status, ticks=len(rows),
        duration_s=float(ticks["t_s"][rows[-1]] - ticks["t_s"][rows[0]]),
        raised_foot_rms_mm=rms(raised), raised_foot_max_mm=max(raised, default=0.0),
        holding_rms_mm=rms(holding),
        stance_travel_max_mm=1e3 * float(travel.max(initial=0.0)),
        max_tilt_deg=float(_tilt_deg(q_true[:, 3:7]).max()),
        final_foot_forces_n=[float(f) for f in truth["foot_force_n"][truth_rows[-1]]],
        estimate=errors.summary())
