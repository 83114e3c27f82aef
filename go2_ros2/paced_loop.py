"""Runs a simulated control loop on the wall clock, for the simulated GO2's ROS 2 node: one
control tick per period of wall time, so that ROS 2 clients, which wait and time on their own
clocks, see the robot move at its real speed (``/clock`` carries the simulated time).
"""

from __future__ import annotations

import time
from typing import Any

#: Behind the wall clock by more than this [s] (a loaded machine), the loop stops catching
#: up and restarts its grid from now, so it never runs a burst of ticks.
MAX_LAG_S = 0.05


class PacedLoop:
    """Ticks ``loop`` at its control period on the wall clock until :meth:`request_stop`.

    Args:
        loop: A control loop with ``spin_once()``, ``controller.control_period_s`` and
            ``robot.time_s`` [s].
        real_time_factor: Simulated seconds per wall-clock second (1: real time).
    """

    def __init__(self, loop: Any, *, real_time_factor: float = 1.0) -> None:
        if not (real_time_factor > 0.0):
            raise ValueError(f"real_time_factor must be > 0; received {real_time_factor!r}")
        self.loop = loop
        self.period_s = loop.controller.control_period_s / real_time_factor
        self.ticks = 0
        self.resyncs = 0
        self._stop = False

    def request_stop(self) -> None:
        """Stop after the current tick (any thread, or a signal handler)."""
        self._stop = True

    def run(self, *, duration_s: float | None = None) -> None:
        """Tick until stopped, or for ``duration_s`` of simulated time [s]."""
        end_s = None if duration_s is None else self.loop.robot.time_s + duration_s - 1e-9
        start = time.monotonic()
        index = 0
        while not self._stop and (end_s is None or self.loop.robot.time_s < end_s):
            self.loop.spin_once()
            self.ticks += 1
            index += 1
            deadline = start + index * self.period_s
            wait = deadline - time.monotonic()
            if wait > 0.0:
                time.sleep(wait)
            elif wait < -MAX_LAG_S:
                start, index = time.monotonic(), 0
                self.resyncs += 1
