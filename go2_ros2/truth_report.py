"""What each goal served by the simulated GO2's ROS 2 node did, measured on the simulator's
truth (``go2-wbc ros2 --truth-report FILE.json``): the same figures as a run across processes
(:func:`sim.dds_evaluation.goal_runs`: the raised foot against its target, the tilt, the feet's
forces at the end, the estimate's errors), from a tick hook that keeps, every control tick,
the estimate, the contact schedule and the foot targets beside the simulator's state.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from actions.goal_status import GoalStatus
from sim.dds_evaluation import goal_runs
from wbc.model.description import LEGS

#: The truth's configuration is written every this many ticks.
TRUTH_EVERY = 4


class TruthReport:
    """A tick hook of a simulated control loop (:class:`sim.control_loop.ControlLoop`) that
    keeps what :func:`sim.dds_evaluation.goal_runs` needs, and writes its figures per goal.

    Args:
        loop: The simulated control loop (its ``sim`` is the truth).
    """

    def __init__(self, loop: Any) -> None:
        self.loop = loop
        self.actions = list(loop.runner.server_names)
        self._rows: list[dict[str, Any]] = []
        self._tick = 0

    def tick_hook(self, loop: Any, output: Any) -> None:
        """Keep this tick's row (a ``ControlLoop`` tick hook)."""
        sim = loop.sim
        q_true, v_true = sim.state()
        stance = loop.controller.schedule.stance
        targets = np.full((len(LEGS), 3), math.nan)
        for k, leg in enumerate(LEGS):
            if not stance[k]:
                target = loop.controller.foot_target(leg)
                if target is not None:
                    targets[k] = target
        goals = loop.runner.active_goals()
        self._tick += 1
        self._rows.append({
            "tick": self._tick, "t_s": loop.context.now_s, "q": loop.context.q.copy(),
            "v": loop.context.v.copy(), "swing": ~np.asarray(stance, dtype=bool),
            "foot_target": targets,
            "goal_status": int(goals[0].status) if goals else 0,
            "goal_action": self.actions.index(goals[0].server.action_name) if goals else -1,
            "q_true": q_true, "v_true": v_true,
            "foot_position_m": sim.foot_position_array().copy(),
            "foot_force_n": np.asarray(sim.foot_normal_forces(), dtype=float).copy()})

    def figures(self) -> list[dict[str, Any]]:
        """Each goal's figures (:class:`sim.dds_evaluation.GoalRunMetrics` as a dict), in the
        order the goals ran."""
        if not self._rows:
            return []
        rows = self._rows

        def column(name: str) -> np.ndarray:
            return np.array([row[name] for row in rows])

        ticks = {"state_tick": column("tick"), "fresh": np.ones(len(rows), dtype=bool),
                 "t_s": column("t_s"), "q": column("q"), "v": column("v"),
                 "swing": column("swing"), "foot_target": column("foot_target"),
                 "goal_status": column("goal_status"), "goal_action": column("goal_action"),
                 "goal_status_names": np.array([GoalStatus(k).name for k in range(7)]),
                 "action_names": np.array(self.actions)}
        truth = {"tick": column("tick"), "q": column("q_true"), "v": column("v_true"),
                 "foot_position_m": column("foot_position_m"),
                 "foot_force_n": column("foot_force_n")}
        return [run.as_dict() for run in goal_runs(ticks, truth)]

    def truth_samples(self, every: int = TRUTH_EVERY) -> dict[str, list[Any]]:
        """The simulator's time [s] and exact configuration (19,) every ``every`` ticks, to
        compare what the node published (``/odom``) with."""
        kept = self._rows[::every]
        return {"t_s": [float(row["t_s"]) for row in kept],
                "q": [row["q_true"].tolist() for row in kept]}

    def write(self, path: Path | str) -> int:
        """Write :meth:`figures` and :meth:`truth_samples` as JSON; returns the number of
        goals."""
        figures = self.figures()
        Path(path).write_text(json.dumps({"goals": figures, "truth": self.truth_samples()})
                              + "\n")
        return len(figures)
