"""An MP4 of a run, rendered offscreen from a camera that tracks the GO2's base."""

from __future__ import annotations

import ctypes.util
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sim.viewer import follow_base, has_display

if TYPE_CHECKING:
    from sim.control_loop import ControlLoop
    from sim.scene_overlay import SceneOverlay
    from sim.simulator import Go2Simulator
    from wbc.control_output import ControlOutput


class VideoRecorder:
    """Renders a camera tracking the base at ``fps`` frames per simulated second to an MP4.

    With an ``overlay`` (:class:`sim.scene_overlay.SceneOverlay`), each frame also shows
    its geoms and, at the top left, its caption (the goal's phase and progress, the time).
    """

    def __init__(self, sim: Go2Simulator, path: Path, *, fps: int, size: tuple[int, int],
                 overlay: SceneOverlay | None = None):
        import imageio
        import mujoco

        width, height = size
        self.aspect = width / height
        vis = sim.model.vis
        saved = (vis.global_.offwidth, vis.global_.offheight, vis.quality.offsamples,
                 vis.quality.shadowsize)
        vis.global_.offwidth = max(vis.global_.offwidth, width)
        vis.global_.offheight = max(vis.global_.offheight, height)
        if not has_display():
            # Software GL: a 4096 px shadow map and 4x multisampling cost ~0.4 s a frame;
            # 1024 px and none keep it near 0.1 s.
            vis.quality.offsamples = 0
            vis.quality.shadowsize = min(vis.quality.shadowsize, 1024)
        try:
            self.renderer = mujoco.Renderer(sim.model, height=height, width=width)
        finally:
            (vis.global_.offwidth, vis.global_.offheight, vis.quality.offsamples,
             vis.quality.shadowsize) = saved
        self.camera = mujoco.MjvCamera()
        follow_base(self.camera, sim.model)
        self.sim = sim
        self.overlay = overlay
        self.period_s = 1.0 / fps
        self.next_s = sim.time_s
        self.frames = 0
        self.writer = imageio.get_writer(path, fps=fps, codec="libx264", quality=7,
                                         macro_block_size=2)

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        if self.sim.time_s + 1e-9 < self.next_s:
            return
        self.next_s += self.period_s
        self.writer.append_data(self.render(loop))
        self.frames += 1

    def render(self, loop: ControlLoop) -> np.ndarray:
        """The current frame (height, width, 3), with the overlay if there is one."""
        self.renderer.update_scene(self.sim.data, self.camera)
        if self.overlay is not None:
            self.overlay.draw(self.renderer.scene, loop)
            self.overlay.draw_caption(self.renderer.scene, loop, aspect=self.aspect)
        return self.renderer.render()

    def close(self) -> None:
        """Finish the file and free the GL context."""
        self.writer.close()
        self.renderer.close()


def choose_offscreen_gl() -> None:
    """Pick a MuJoCo GL backend that renders without a display, before mujoco is imported.

    Respects a ``MUJOCO_GL`` the user set. OSMesa (``libosmesa6``, installed by
    ``scripts/setup.sh``) is preferred; EGL is used when only it is present.
    """
    if os.environ.get("MUJOCO_GL") or has_display():
        return
    if ctypes.util.find_library("OSMesa") or not ctypes.util.find_library("EGL"):
        os.environ["MUJOCO_GL"] = "osmesa"
    else:
        os.environ["MUJOCO_GL"] = "egl"
