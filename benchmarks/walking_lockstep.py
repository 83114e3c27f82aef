"""The walking tick against the standing tick, in lockstep: two loops in one process taking turns.

A machine shared with other processes runs slower or faster from one second to the next by
more than walking costs; two loops that take turns of :data:`TURN_TICKS` ticks see the same
load, so the ratio of their turns' medians is what another machine would see.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmarks.timed_ticks import TimedTicks, stats_us
from sim.episode import Episode
from sim.episode_loop import build_loop
from sim.gait_view import walking_motion
from wbc.locomotion.walking import Walking

#: Ticks a loop runs before the other takes its turn.
TURN_TICKS = 100
#: The parts of the tick compared.
LOCKSTEP_PARTS = ("controller", "actions", "estimator", "physics", "tick")


def lockstep(walk: Episode, *, settle_s: float, walk_s: float,
             turn_ticks: int = TURN_TICKS) -> dict[str, Any]:
    """Run ``walk`` (a Walk goal's episode) and the same robot standing, in turns.

    Both loops stand ``settle_s`` [s], then the walking one is sent ``walk``'s goal; they take
    turns until the walking loop has run ``walk_s`` [s] from the goal. Each tick is timed by
    :class:`TimedTicks` on the wall clock.

    Returns:
        ``walking_us`` (the walking loop's ticks in the walking phase) and ``standing_us``
        (every standing tick): per part, median, p99 and mean [us]; ``turn_ratios``: per part,
        the 10th, 50th and 90th percentiles over the turns of the walking turn's median over
        the standing turn's that follows it (turns with at least half their ticks walking);
        ``turns``: how many.
    """
    stand = Episode(action=None, state=walk.state, control_period_s=walk.control_period_s,
                    settle_s=settle_s, after_s=walk_s)
    walking_loop, standing_loop = build_loop(walk), build_loop(stand)
    for loop in (walking_loop, standing_loop):
        loop.spin_for(settle_s)
    walking_loop.client("walk").send_goal_async(walk.goal)
    walk_ticks, stand_ticks = TimedTicks(walking_loop), TimedTicks(standing_loop)
    walking: list[bool] = []
    ratios: dict[str, list[float]] = {part: [] for part in LOCKSTEP_PARTS}
    end_s = walking_loop.robot.time_s + walk_s - 1e-9
    while walking_loop.robot.time_s < end_s:
        first = len(walking)
        for _ in range(turn_ticks):
            walk_ticks()
            motion = walking_motion(walking_loop)
            walking.append(isinstance(motion, Walking) and str(motion.phase) == "walking")
        for _ in range(turn_ticks):
            stand_ticks()
        turn = np.array(walking[first:])
        if turn.sum() < turn_ticks // 2:
            continue
        for part in LOCKSTEP_PARTS:
            mine = np.asarray(walk_ticks.samples[part][first:])[turn]
            theirs = stand_ticks.samples[part][-turn_ticks:]
            ratios[part].append(float(np.median(mine) / max(np.median(theirs), 1e-12)))
    mask = np.array(walking)
    return {
        "turn_ticks": turn_ticks, "turns": len(ratios["tick"]),
        "walking_us": {part: stats_us(np.asarray(walk_ticks.samples[part])[mask])
                       for part in LOCKSTEP_PARTS},
        "standing_us": {part: stats_us(stand_ticks.samples[part]) for part in LOCKSTEP_PARTS},
        "turn_ratios": {part: [float(np.percentile(values, p)) for p in (10, 50, 90)]
                        if values else [float("nan")] * 3 for part, values in ratios.items()},
    }
