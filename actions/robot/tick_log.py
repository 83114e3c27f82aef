"""Per-tick arrays of a wall-clock control loop, saved as ``.npz``: what the controller saw
(the state's robot tick, the estimate), what it did (status, command torques, swing feet and
their targets), where the goal was, and each tick's timing.

``state_tick`` is the robot's ``LowState_.tick`` the tick's command answers (the command's
``reserve``): join these rows with a robot's or a simulator bridge's own log by it. Arrays are
kept in chunks of :data:`CHUNK_TICKS` rows: about 0.3 kB a tick (160 kB/s at 500 Hz).
Chunks are small so that each comes from the heap: chunks of 4096 rows (1.3 MB, memory
mapped afresh each time) stalled the tick that made one for 0.3 to 2.5 ms, a missed
deadline at 1 kHz.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from actions.goal_status import GoalStatus
from actions.robot.rest_sequence import Phase
from actions.robot.robot_capabilities import AnswersTicks
from actions.robot.tick_stats import SERIES
from wbc.controller.control_output import ControlStatus
from wbc.model.description import JOINT_NAMES, LEGS

if TYPE_CHECKING:
    from actions.robot.realtime_loop import RealtimeLoop

#: Rows allocated at a time (about 80 kB: below the C library's threshold for mapping memory).
CHUNK_TICKS = 256
_STATUSES = tuple(ControlStatus)
#: Column -> (shape of a row, dtype).
COLUMNS: dict[str, tuple[tuple[int, ...], str]] = {
    "t_s": ((), "f8"),              # robot time [s] at the tick's start
    "state_tick": ((), "i8"),       # LowState_.tick answered (-1: the robot has none)
    "fresh": ((), "?"),             # a new state this tick
    "q": ((19,), "f4"),             # the estimate (Pinocchio convention, JOINT_NAMES)
    "v": ((18,), "f4"),
    "estimate_flags": ((), "i4"),   # the estimator's fault flags
    "control_status": ((), "i1"),   # index in control_status_names; -1 while damping
    "tau_ff": ((12,), "f4"),        # the command's feed-forward torques [N m]; NaN: damping
    "swing": ((4,), "?"),           # each leg (LEGS) out of the contact schedule: raised
    "foot_target": ((4, 3), "f4"),  # a swing foot's world target [m]; NaN in stance
    "phase": ((), "i1"),            # the stop phase (phase_names)
    "goal_status": ((), "i1"),      # the running goal's GoalStatus (0: none)
    "goal_action": ((), "i1"),      # its action, index in action_names (-1: none)
    "stage_s": ((len(SERIES),), "f4"),  # tick_stats.SERIES [s]
    "missed": ((), "?"),            # the tick overran the next deadline
}


@runtime_checkable
class FootTargets(Protocol):
    """A controller that says where a swing foot is going (the whole-body controller)."""

    def foot_target(self, leg: str) -> np.ndarray | None:
        """The world target [m] of ``leg``'s foot while it swings (``None``: none)."""


class TickLog:
    """Records one row per tick of a :class:`~actions.robot.realtime_loop.RealtimeLoop`.

    Add :meth:`record` to its ``callbacks``; :meth:`save` writes the ``.npz``. A row's
    ``stage_s`` and ``missed`` are written at the next tick (or by :meth:`save`), once known.
    """

    def __init__(self) -> None:
        self._chunks: list[dict[str, np.ndarray]] = []
        self._row = CHUNK_TICKS  # no chunk yet
        self._actions: tuple[str, ...] = ()
        self._pending: tuple[dict[str, np.ndarray], int] | None = None
        #: What the loop's robot and controller declare, found at the first row.
        self._ticks: AnswersTicks | None = None
        self._targets: FootTargets | None = None
        self._declared = False

    def __len__(self) -> int:
        return 0 if not self._chunks else (len(self._chunks) - 1) * CHUNK_TICKS + self._row

    def record(self, rt: RealtimeLoop) -> None:
        """Append this tick's row (a ``RealtimeLoop`` callback)."""
        self._finish_pending(rt.last_times, missed=rt.missed)
        if self._row == CHUNK_TICKS:
            self._chunks.append({name: np.zeros((CHUNK_TICKS, *shape), dtype=dtype)
                                 for name, (shape, dtype) in COLUMNS.items()})
            self._row = 0
        chunk, i = self._chunks[-1], self._row
        self._row += 1
        self._pending = (chunk, i)
        loop = rt.loop
        if not self._declared:  # once: an isinstance on a protocol costs microseconds
            self._declared = True
            robot, controller = loop.robot.robot, loop.controller
            self._ticks = robot if isinstance(robot, AnswersTicks) else None
            self._targets = controller if isinstance(controller, FootTargets) else None
        estimator = loop.estimator
        chunk["t_s"][i] = loop.context.now_s
        chunk["state_tick"][i] = -1 if self._ticks is None else self._ticks.answer_tick
        chunk["fresh"][i] = rt.fresh
        chunk["q"][i] = loop.context.q
        chunk["v"][i] = loop.context.v
        chunk["estimate_flags"][i] = 0 if estimator is None else estimator.estimate.flags
        out = rt.last_output
        chunk["control_status"][i] = -1 if out is None else _STATUSES.index(out.status)
        chunk["tau_ff"][i] = math.nan if out is None else out.tau_ff
        stance = loop.controller.schedule.stance
        targets = chunk["foot_target"][i]
        targets[:] = math.nan
        with_targets = self._targets
        for k, leg in enumerate(LEGS):
            chunk["swing"][i, k] = not stance[k]
            if not stance[k] and with_targets is not None:
                target = with_targets.foot_target(leg)
                if target is not None:
                    targets[k] = target
        chunk["phase"][i] = int(rt.rest.phase)
        goals = loop.runner.active_goals()
        if not self._actions:
            self._actions = loop.runner.server_names
        chunk["goal_status"][i] = int(goals[0].status) if goals else 0
        chunk["goal_action"][i] = (self._actions.index(goals[0].server.action_name)
                                   if goals else -1)

    def arrays(self, rt: RealtimeLoop | None = None) -> dict[str, Any]:
        """The columns so far, one row per tick, with the names the codes index.

        Args:
            rt: The loop, to complete the last row's timing (after its last tick).
        """
        if rt is not None:
            self._finish_pending(rt.times, missed=rt.missed)
        columns: dict[str, Any] = {
            name: np.concatenate([chunk[name] for chunk in self._chunks])[:len(self)]
            if self._chunks else np.zeros((0, *shape), dtype=dtype)
            for name, (shape, dtype) in COLUMNS.items()}
        columns.update(
            joint_names=np.array(JOINT_NAMES), legs=np.array(LEGS),
            stage_names=np.array(SERIES), phase_names=np.array([p.name for p in Phase]),
            control_status_names=np.array([s.name for s in _STATUSES]),
            goal_status_names=np.array([GoalStatus(k).name for k in range(7)]),
            action_names=np.array(self._actions))
        return columns

    def save(self, path: str | Path, rt: RealtimeLoop | None = None) -> None:
        """Write :meth:`arrays` to ``path`` (``.npz``)."""
        np.savez(path, **self.arrays(rt))

    def _finish_pending(self, times: np.ndarray, *, missed: bool) -> None:
        if self._pending is not None:
            chunk, i = self._pending
            chunk["stage_s"][i] = times
            chunk["missed"][i] = missed
            self._pending = None
