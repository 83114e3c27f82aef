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
    from wbc.controller.control_output import ControlOutput


#: Height [px] of the legend's text in a 480 px tall frame; it scales with the frame.
LEGEND_FONT_PX = 13
#: Frames less tall than this [px] get no legend: its text would be too small to read.
LEGEND_MIN_HEIGHT_PX = 240


class VideoRecorder:
    """Renders a camera tracking the base at ``fps`` frames per simulated second to an MP4.

    With an ``overlay`` (:class:`sim.scene_overlay.SceneOverlay`), each frame also shows
    its geoms, at the top left its caption (the goal's phase and progress, the time) and at
    the bottom left its legend (what each colour is, for the overlays that are on; not in
    frames less than :data:`LEGEND_MIN_HEIGHT_PX` tall, or with ``legend=False``). The
    legend is drawn again when the overlay's changes (a walk starts: the gait's colours).
    """

    def __init__(self, sim: Go2Simulator, path: Path, *, fps: int, size: tuple[int, int],
                 overlay: SceneOverlay | None = None, legend: bool = True):
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
        #: Whether frames get a legend (asked for, and tall enough to read it).
        self.legend_on = legend and height >= LEGEND_MIN_HEIGHT_PX
        self._legend_entries: list[tuple[str, tuple[float, ...], str]] = []
        #: Stamps the legend into a frame (None: no legend).
        self.legend: LegendStamp | None = None
        self._update_legend()
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
            self._update_legend()
        frame = self.renderer.render()
        if self.legend is not None and self.overlay is not None:
            self.legend.stamp(frame)
        return frame

    def _update_legend(self) -> None:
        """A new stamp when the overlay's legend differs from the one stamped (2 ms)."""
        if not self.legend_on or self.overlay is None:
            return
        entries = self.overlay.legend()
        if entries != self._legend_entries:
            self._legend_entries = entries
            self.legend = (LegendStamp(entries, frame_height=self.renderer.height)
                           if entries else None)

    def close(self) -> None:
        """Finish the file and free the GL context."""
        self.writer.close()
        self.renderer.close()


class LegendStamp:
    """A legend, drawn once (coloured swatches and their labels on a translucent dark box),
    blended into each frame's bottom left corner.

    Blending the box into a 640x480 frame costs about 0.13 ms (on 2 cores), under 1 % of
    rendering the frame on software GL; drawing it, once, 2 ms.

    Args:
        entries: ``(colour name, RGBA, text)`` per row
            (:meth:`sim.scene_overlay.SceneOverlay.legend`).
        frame_height: Height [px] of the frames: the text is :data:`LEGEND_FONT_PX` tall in
            480, in proportion otherwise (at least 9 px).
    """

    def __init__(self, entries: list[tuple[str, tuple[float, ...], str]], *,
                 frame_height: int):
        from PIL import Image, ImageDraw, ImageFont

        font_px = max(9, round(LEGEND_FONT_PX * frame_height / 480))
        font = ImageFont.load_default(size=font_px)
        pad, row, swatch = max(3, font_px // 2), round(1.4 * font_px), font_px
        measure = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
        text_px = max(round(measure.textlength(text, font=font)) for _, _, text in entries)
        width, height = 3 * pad + swatch + text_px, 2 * pad + row * len(entries) - (row - swatch)
        image = Image.new("RGBA", (width, height), (0, 0, 0, 150))
        draw = ImageDraw.Draw(image)
        #: Where each row's swatch is centred in the box, (column, row) [px].
        self.swatch_centres_px: list[tuple[int, int]] = []
        for i, (_, rgba, text) in enumerate(entries):
            top = pad + i * row
            self.swatch_centres_px.append((pad + swatch // 2, top + swatch // 2))
            colour = tuple(round(255 * c) for c in rgba[:3]) + (255,)
            draw.rectangle((pad, top, pad + swatch - 1, top + swatch - 1), fill=colour)
            draw.text((2 * pad + swatch, top + swatch / 2), text, font=font,
                      fill=(255, 255, 255, 255), anchor="lm")
        rgba_px = np.asarray(image, dtype=np.float32) / 255.0
        alpha = rgba_px[..., 3:]
        #: The box's colour times its opacity [0, 255], and what a frame keeps (1 - opacity).
        self.paint = rgba_px[..., :3] * alpha * 255.0 + 0.5  # + 0.5: rounds, not truncates
        self.keep = 1.0 - alpha
        #: Gap [px] between the box and the frame's left and bottom edges.
        self.margin_px = pad
        self.entries = list(entries)

    @property
    def size(self) -> tuple[int, int]:
        """The box's (width, height) [px]."""
        return self.paint.shape[1], self.paint.shape[0]

    def stamp(self, frame: np.ndarray) -> np.ndarray:
        """Blend the legend into ``frame`` (height, width, 3; uint8) in place; returns it.

        A frame too small for the box is left as it is.
        """
        width, height = self.size
        bottom = frame.shape[0] - self.margin_px
        left = self.margin_px
        if bottom - height < 0 or left + width > frame.shape[1]:
            return frame
        region = frame[bottom - height:bottom, left:left + width]
        region[...] = region * self.keep + self.paint
        return frame


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
