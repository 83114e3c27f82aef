"""The MuJoCo viewer window, wall-clock pacing, and whether a display is there to open one."""

from __future__ import annotations

import os
import time
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from sim.control_loop import ControlLoop
    from sim.simulator import Go2Simulator
    from wbc.control_output import ControlOutput


def has_display() -> bool:
    """Whether a window can be opened ($DISPLAY or $WAYLAND_DISPLAY is set)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def window_problem() -> str:
    """Why the viewer's window cannot open ('' when it can)."""
    if not has_display():
        return "no display ($DISPLAY and $WAYLAND_DISPLAY are unset)"
    import warnings

    import glfw  # the viewer's windowing library, a dependency of mujoco

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # glfw warns, then returns False
        if not glfw.init():
            display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
            return f"cannot connect to the display {display!r}"
    glfw.terminate()
    return ""


class ViewerHook:
    """Keeps a passive MuJoCo viewer in sync, about 60 times a simulated second."""

    def __init__(self, sim: Go2Simulator):
        import mujoco.viewer

        self.handle = mujoco.viewer.launch_passive(sim.model, sim.data, show_left_ui=False,
                                                   show_right_ui=False)
        self.sim = sim
        self.next_s = 0.0

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if self.sim.time_s >= self.next_s and self.handle.is_running():
            self.handle.sync()
            self.next_s = self.sim.time_s + 1.0 / 60.0

    def close(self) -> None:
        """Close the window."""
        self.handle.close()


class Pacer:
    """Sleeps so that simulated time does not run ahead of the wall clock (``--realtime``)."""

    def __init__(self, sim: Go2Simulator):
        self.sim = sim
        self.start_wall = time.perf_counter()
        self.start_sim = sim.time_s

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        ahead = (self.sim.time_s - self.start_sim) - (time.perf_counter() - self.start_wall)
        if ahead > 2e-3:  # below the sleep granularity, catch up on a later tick
            time.sleep(ahead)
