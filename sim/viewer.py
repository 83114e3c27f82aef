"""The MuJoCo viewer window, wall-clock pacing, and whether a display is there to open one."""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import mujoco

    from sim.control_loop import ControlLoop
    from sim.scene_overlay import SceneOverlay
    from sim.simulator import Go2Simulator
    from wbc.controller.control_output import ControlOutput

#: The view the viewer opens with and videos are shot from: the base tracked from its front
#: right, low enough to see the sky, high enough to see the support polygon between the feet.
CAMERA_DISTANCE_M, CAMERA_AZIMUTH_DEG, CAMERA_ELEVATION_DEG = 1.6, 120.0, -25.0
#: What the window says while it holds the final state (:meth:`ViewerHook.hold`): its two
#: columns, tab-separated.
HOLD_NOTE = "paused\tthe final state: close the window to exit"
#: Longest wait [s] for the viewer's render loop to end when it is closed.
CLOSE_TIMEOUT_S = 5.0


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
    draws the overlay's geoms into the viewer's user scene at every sync, shows its text
    panel (the goal's phase and progress, the support feet, the CoM margin, the normal
    forces) at the top left and its legend (what each colour is) at the bottom left.

    The viewer's ``set_texts`` waits until the window has taken the texts, about one frame
    (0.1 s on software GL): a thread of this hook waits for it, with the latest panel, so
    the control loop never does.

    A window its user closes, or that is destroyed, ends nothing: the hook notices at its
    next sync, calls ``on_closed`` once and does nothing more; the run goes on without it.
    No viewer call raises out of the hook. At the end, :meth:`hold` keeps the window on the
    final state until its user closes it.
    """

    def __init__(self, sim: Go2Simulator, *, overlay: SceneOverlay | None = None,
                 handle: Any = None, on_closed: Callable[[], None] | None = None):
        """Args:
            sim: The simulator whose model and data the window shows.
            overlay: What to draw over the robot (nothing by default).
            handle: An open viewer handle (default: a passive viewer launched here).
            on_closed: Called once, from the control loop's thread, when the hook finds the
                window closed by its user or destroyed before :meth:`close` (its sim time
                is then :attr:`closed_at_s`, the exception if one told it :attr:`error`).
        """
        #: The viewer's own threads (its render loop), joined by :meth:`close`.
        self._viewer_threads: list[threading.Thread] = []
        if handle is None:
            import mujoco.viewer

            before = set(threading.enumerate())
            handle = mujoco.viewer.launch_passive(sim.model, sim.data, show_left_ui=False,
                                                  show_right_ui=False)
            self._viewer_threads = [t for t in threading.enumerate() if t not in before]
        self.handle = handle
        with self.handle.lock():
            follow_base(self.handle.cam, sim.model)
        self.sim = sim
        self.overlay = overlay
        self.on_closed = on_closed
        self.next_s = 0.0
        #: Sim time [s] the window was found closed by its user or destroyed (None: not).
        self.closed_at_s: float | None = None
        #: The exception a viewer call raised when the window went (None: it just closed).
        self.error: BaseException | None = None
        self._gone = False  # the window closed or failed, or close() was called
        self._texts: list[tuple[Any, ...]] | None = None  # the latest texts, not yet shown
        self._texts_lock = threading.Lock()
        self._wake = threading.Event()
        self._closing = False
        self._texts_done = False
        self._text_error: BaseException | None = None
        self._texter = threading.Thread(target=self._show_texts, name="viewer texts",
                                        daemon=True)
        self._texter.start()

    @property
    def is_open(self) -> bool:
        """Whether the window is still there (and :meth:`close` was not called)."""
        return not self._gone and self._running()

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if self._gone or self.sim.time_s < self.next_s:
            return
        if self._text_error is not None or not self._running():
            self._window_gone(self._text_error)
            return
        try:
            if self.overlay is not None:
                self.draw_overlay(loop)
            self.handle.sync()
        except Exception as err:  # noqa: BLE001 - a destroyed window fails in assorted types
            self._window_gone(err)
            return
        self.next_s = self.sim.time_s + 1.0 / 60.0

    def draw_overlay(self, loop: ControlLoop) -> None:
        """Replace the user scene's geoms with the overlay's; post its text panel and legend."""
        self._draw_geoms(loop)
        texts = self._texts_of(loop)
        if texts:
            with self._texts_lock:
                self._texts = texts
            self._wake.set()

    def hold(self, loop: ControlLoop, *, poll_s: float = 0.1,
             sleep: Callable[[float], None] | None = None) -> bool:
        """Show the final state, paused, until the window's user closes it.

        The simulation does not advance: the window shows the state the run ended in (what
        its result, metrics and outputs describe), and its user can turn the camera, make
        the robot transparent, and so on. The panel says so, at the top right.

        Args:
            loop: The control loop whose final state to show.
            poll_s: How often to look whether the window is still open [s].
            sleep: Waits ``poll_s`` (default ``time.sleep``).

        Returns:
            Whether the window was open to hold (False: it had gone, or the hook is closed).
        """
        if not self.is_open:
            return False
        sleep = sleep or time.sleep
        self._stop_texts()  # the panel last posted is shown; nothing the thread sends follows
        try:
            self._draw_geoms(loop)
            self.handle.sync()
            self.handle.set_texts(self._texts_of(loop, note=HOLD_NOTE))
        except Exception as err:  # noqa: BLE001 - a destroyed window fails in assorted types
            self._gone, self.error = True, err
            return False
        while self._running():
            sleep(poll_s)
        self._gone = True
        return True

    def close(self) -> None:
        """Show the last texts posted, stop the text thread, close the window; never raises,
        and does nothing the second time."""
        if self._closing:
            return
        self._closing = True
        self._stop_texts()
        self._gone = True
        with contextlib.suppress(Exception):
            self.handle.close()
        # The render loop ends on its own thread (a daemon). An interpreter that exits while
        # it still draws terminates GLFW under it (MuJoCo's exit hook): a segmentation fault.
        for thread in self._viewer_threads:
            thread.join(timeout=CLOSE_TIMEOUT_S)

    # -------------------------------------------------------------------------- inside

    def _running(self) -> bool:
        try:
            return bool(self.handle.is_running())
        except Exception:  # noqa: BLE001 - a destroyed window fails in assorted types
            return False

    def _window_gone(self, err: BaseException | None = None) -> None:
        """The window was closed by its user or destroyed: note it, say it once."""
        self._gone = True
        self.closed_at_s, self.error = self.sim.time_s, err
        self._wake.set()  # the text thread ends
        if self.on_closed is not None:
            self.on_closed()

    def _draw_geoms(self, loop: ControlLoop) -> None:
        if self.overlay is not None:
            with self.handle.lock():  # the window's thread renders the user scene
                scene = self.handle.user_scn
                scene.ngeom = 0
                self.overlay.draw(scene, loop)

    def _texts_of(self, loop: ControlLoop, *, note: str = "") -> list[tuple[Any, ...]]:
        """The panel (top left), the legend (bottom left), ``note`` (top right)."""
        import mujoco

        grid = mujoco.mjtGridPos
        texts: list[tuple[Any, ...]] = []
        if self.overlay is not None:
            texts.append((None, grid.mjGRID_TOPLEFT, *self.overlay.status_lines(loop)))
            if self.overlay.overlays:
                texts.append((None, grid.mjGRID_BOTTOMLEFT, *self.overlay.legend_lines()))
        if note:
            texts.append((None, grid.mjGRID_TOPRIGHT, *note.split("\t")))
        return texts

    def _stop_texts(self) -> None:
        """End the text thread once it has shown the texts last posted (if the window takes
        them: one that is gone may never, and the thread, a daemon, is then left waiting)."""
        self._texts_done = True
        self._wake.set()
        self._texter.join(timeout=5.0 if self._running() else 0.5)

    def _show_texts(self) -> None:
        """The text thread: hands the latest posted texts to the window, until closed."""
        while True:
            self._wake.wait()
            self._wake.clear()
            with self._texts_lock:
                texts, self._texts = self._texts, None
            if texts is not None and self._running():
                try:
                    self.handle.set_texts(texts)
                except Exception as err:  # noqa: BLE001 - the window's failures vary
                    self._text_error = err  # the control loop's thread reports it
                    return
            if self._gone or self._texts_done:
                return


class Pacer:
    """Sleeps so that simulated time does not run ahead of the wall clock (``--realtime``).

    Setting :attr:`active` to False stops the pacing for good (the command line does when
    the viewer that asked for it is closed).
    """

    def __init__(self, sim: Go2Simulator):
        self.sim = sim
        self.start_wall = time.perf_counter()
        self.start_sim = sim.time_s
        self.active = True

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if not self.active:
            return
        ahead = (self.sim.time_s - self.start_sim) - (time.perf_counter() - self.start_wall)
        if ahead > 2e-3:  # below the sleep granularity, catch up on a later tick
            time.sleep(ahead)
