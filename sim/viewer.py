"""The MuJoCo viewer window, wall-clock pacing, and whether a display is there to open one."""

from __future__ import annotations

import os
import threading
import time
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import mujoco

    from sim.control_loop import ControlLoop
    from sim.scene_overlay import SceneOverlay
    from sim.simulator import Go2Simulator
    from wbc.control_output import ControlOutput

#: The view the viewer opens with and videos are shot from: the base tracked from its front
#: right, low enough to see the sky, high enough to see the support polygon between the feet.
CAMERA_DISTANCE_M, CAMERA_AZIMUTH_DEG, CAMERA_ELEVATION_DEG = 1.6, 120.0, -25.0


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


def follow_base(camera: mujoco.MjvCamera, model: mujoco.MjModel) -> None:
    """Point ``camera`` at the GO2's base and track it, from the default view."""
    import mujoco

    camera.type = mujoco.mjtCamera.mjCAMERA_TRACKING
    camera.trackbodyid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "base")
    camera.distance = CAMERA_DISTANCE_M
    camera.azimuth, camera.elevation = CAMERA_AZIMUTH_DEG, CAMERA_ELEVATION_DEG


class ViewerHook:
    """Keeps a passive MuJoCo viewer in sync, about 60 times a simulated second.

    The window opens on the base, tracked (:func:`follow_base`). With an ``overlay`` it
    draws the overlay's geoms into the viewer's user scene at every sync, and shows its
    text panel (the goal's phase and progress, the support feet, the CoM margin, the normal
    forces) at the top left.

    The viewer's ``set_texts`` waits until the window has taken the texts, about one frame
    (0.1 s on software GL): a thread of this hook waits for it, with the latest panel, so
    the control loop never does.
    """

    def __init__(self, sim: Go2Simulator, *, overlay: SceneOverlay | None = None,
                 handle: Any = None):
        """Args:
            sim: The simulator whose model and data the window shows.
            overlay: What to draw over the robot (nothing by default).
            handle: An open viewer handle (default: a passive viewer launched here).
        """
        if handle is None:
            import mujoco.viewer

            handle = mujoco.viewer.launch_passive(sim.model, sim.data, show_left_ui=False,
                                                  show_right_ui=False)
        self.handle = handle
        with self.handle.lock():
            follow_base(self.handle.cam, sim.model)
        self.sim = sim
        self.overlay = overlay
        self.next_s = 0.0
        self._texts: tuple[str, str] | None = None  # the latest panel, not yet shown
        self._texts_lock = threading.Lock()
        self._wake = threading.Event()
        self._closing = False
        self._texter: threading.Thread | None = None
        if overlay is not None:
            self._texter = threading.Thread(target=self._show_texts, name="viewer texts",
                                            daemon=True)
            self._texter.start()

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if self.sim.time_s >= self.next_s and self.handle.is_running():
            if self.overlay is not None:
                self.draw_overlay(loop)
            self.handle.sync()
            self.next_s = self.sim.time_s + 1.0 / 60.0

    def draw_overlay(self, loop: ControlLoop) -> None:
        """Replace the user scene's geoms with the overlay's; post its text panel."""
        overlay = self.overlay
        if overlay is None:
            return
        with self.handle.lock():  # the window's thread renders the user scene
            scene = self.handle.user_scn
            scene.ngeom = 0
            overlay.draw(scene, loop)
        with self._texts_lock:
            self._texts = overlay.status_lines(loop)
        self._wake.set()

    def _show_texts(self) -> None:
        """The text thread: hands the latest posted panel to the window, until closed."""
        import mujoco

        while True:
            self._wake.wait()
            self._wake.clear()
            with self._texts_lock:
                texts, self._texts = self._texts, None
            if texts is not None and self.handle.is_running():
                self.handle.set_texts((None, mujoco.mjtGridPos.mjGRID_TOPLEFT, *texts))
            if self._closing:
                return

    def close(self) -> None:
        """Show the last panel posted, stop the text thread, close the window."""
        self._closing = True
        self._wake.set()
        if self._texter is not None:
            self._texter.join(timeout=5.0)
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
