"""What the controller is doing, drawn into a MuJoCo scene: CoM, support polygon, forces, target,
gait."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from sim.gait_overlay import GaitOverlay
from sim.gait_view import VELOCITY_UNITS, GaitSource, GaitView
from sim.scene_geoms import (
    ARROW_DRAWN_FRACTION,
    FLOOR_Z,
    ZERO3,
    add_geom,
    connect,
    init_geom,
    next_geom,
    on_floor,
    triangle,
)
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.model.description import FOOT_RADIUS_M, LEGS
from wbc.model.support_polygon import SupportPolygon

if TYPE_CHECKING:
    import mujoco

    from sim.control_loop import ControlLoop

# MuJoCo is imported where it is used, not at the top: the command line parses --overlay
# before it chooses MuJoCo's rendering backend (MUJOCO_GL), which must precede the import.

#: Every overlay, in drawing order.
OVERLAY_NAMES: tuple[str, ...] = ("com", "polygon", "forces", "measured", "target", "gait")
#: What the viewer and the video show unless told otherwise.
DEFAULT_OVERLAYS: tuple[str, ...] = ("com", "polygon", "forces", "target", "gait")
#: Overlay colours (RGBA): saturated hues the scene's greys and blues do not use.
COM_RGBA = (0.95, 0.10, 0.08, 1.0)
POLYGON_RGBA = (0.10, 0.85, 0.25, 1.0)
POLYGON_FILL_RGBA = (0.10, 0.85, 0.25, 0.35)
MARGIN_RGBA = (0.90, 0.95, 0.15, 1.0)
FORCE_RGBA = (1.00, 0.50, 0.00, 1.0)
MEASURED_RGBA = (0.10, 0.35, 1.00, 1.0)
TARGET_RGBA = (0.95, 0.10, 0.85, 0.5)
TRACE_RGBA = (0.95, 0.10, 0.85, 1.0)

#: The legend: per overlay, each colour it draws with, its name and what it shows.
LEGEND: dict[str, tuple[tuple[str, tuple[float, ...], str], ...]] = {
    "com": (("red", COM_RGBA, "centre of mass and its ground point"),),
    "polygon": (("green", POLYGON_RGBA, "support polygon of the loaded feet"),
                ("yellow", MARGIN_RGBA, "support margin: the CoM stays inside")),
    "forces": (("orange", FORCE_RGBA, "commanded contact forces"),),
    "measured": (("blue", MEASURED_RGBA, "measured contact forces"),),
    "target": (("magenta", TRACE_RGBA, "raised foot's target and its trace"),),
}

#: Arrow length per newton [m/N]: a GO2 standing on four feet (about 38 N each) gets 15 cm
#: arrows, on three about 20 cm.
FORCE_SCALE_M_PER_N = 0.004
#: Trace points closer than this [m] to the last one are skipped.
_TRACE_STEP_M = 0.005
#: Most points a trace keeps (the oldest are dropped).
_TRACE_POINTS = 400

def parse_overlays(text: str) -> tuple[str, ...]:
    """Overlay names from a comma-separated list, ``all`` or ``none`` (the CLI's syntax).

    Returns:
        The names in :data:`OVERLAY_NAMES` order, without repeats.

    Raises:
        ConfigurationError: An empty list or an unknown name; the message lists the valid
            names.
    """
    valid = ", ".join(OVERLAY_NAMES)
    words = [w.strip().lower() for w in text.split(",")]
    if words == ["all"]:
        return OVERLAY_NAMES
    if words == ["none"]:
        return ()
    unknown = [w for w in words if w not in OVERLAY_NAMES]
    if unknown or not text.strip():
        raise ConfigurationError(
            f"expected a comma-separated list of {valid}, or all or none; received {text!r}")
    return tuple(name for name in OVERLAY_NAMES if name in words)


class SceneOverlay:
    """Draws the controller's view of the robot as extra geoms in a :class:`mujoco.MjvScene`.

    The overlays (:data:`OVERLAY_NAMES`):

    - ``com``: a red ball at the centre of mass (inside the body: the viewer shows it when
      the model is made transparent, key T), a red line down to the floor and a red disc
      where it meets it;
    - ``polygon``: the support polygon of the loaded feet in green, filled, and inside it,
      in yellow, the polygon shrunk by the controller's support margin: the region the
      controller keeps the CoM in;
    - ``forces``: an orange arrow from each stance foot's contact point, the contact force
      the controller commands, :data:`FORCE_SCALE_M_PER_N` long per newton;
    - ``measured``: a thinner blue arrow beside it, the force MuJoCo measures;
    - ``target``: a translucent magenta ball at each raised foot's target, and the target's
      trace since the foot left the ground;
    - ``gait``: while a motion walks (``gait_of`` finds it), the feet in stance and in swing,
      the planned footholds, the commanded and the measured velocity
      (:class:`sim.gait_overlay.GaitOverlay`); the legend lists them once one was drawn.

    Everything comes from the loop's public state: the centre of mass, the support legs and
    the feet from ``loop.controller``, the margin from its ``config.contacts.support_margin_m``, the
    commanded forces from ``loop.last_output.forces``, the measured ones from ``loop.sim``,
    a swing foot's target from the controller's foot task, the gait from the walking motion
    ``gait_of`` returns (its :class:`sim.gait_view.GaitView` at the controller's state,
    ``loop.context.q``, and feet). The geoms are decor: they take no
    part in the physics and cast no shadow.

    Use it with the viewer (``handle.user_scn``) or an offscreen renderer (``renderer.scene``
    after ``update_scene``); :class:`sim.viewer.ViewerHook` and
    :class:`sim.video_recorder.VideoRecorder` take one, and show its :meth:`legend` (what
    each colour is, for the overlays that are on) beside the robot.

    Example:
        >>> overlay = SceneOverlay(("com", "polygon"))
        >>> renderer.update_scene(loop.sim.data, camera)
        >>> overlay.draw(renderer.scene, loop)
        >>> image = renderer.render()
    """

    def __init__(self, overlays: Iterable[str] = DEFAULT_OVERLAYS, *,
                 force_scale_m_per_n: float = FORCE_SCALE_M_PER_N,
                 status_of: Callable[[], tuple[str, float]] | None = None,
                 gait_of: Callable[[ControlLoop], GaitSource | None] | None = None):
        """Args:
            overlays: Names from :data:`OVERLAY_NAMES`; an empty list draws nothing.
            force_scale_m_per_n: Arrow length per newton of contact force [m/N].
            status_of: Returns the running goal's ``(phase, progress 0..1)`` for the text
                panel (:meth:`status_lines`); the panel leaves them out without it.
            gait_of: Returns the loop's walking motion now, or ``None`` when nothing walks
                (default :func:`sim.gait_view.walking_motion`).

        Raises:
            ConfigurationError: An unknown overlay name (the message lists the valid ones),
                or a scale that is not positive.
        """
        names = tuple(overlays)
        for name in names:
            if name not in OVERLAY_NAMES:
                raise ConfigurationError(
                    f"overlays: unknown overlay {name!r}; valid overlays: "
                    f"{', '.join(OVERLAY_NAMES)}")
        self.overlays = frozenset(names)
        self.force_scale_m_per_n = as_float("force_scale_m_per_n", force_scale_m_per_n,
                                            low=1e-6)
        self.status_of = status_of
        if gait_of is None:
            from sim.gait_view import walking_motion

            gait_of = walking_motion
        self.gait_of = gait_of
        self.gait = GaitOverlay()
        #: Whether a gait was drawn yet (from then on the legend lists its colours).
        self.gait_shown = False
        #: Past targets of each swinging foot since it left the ground [m].
        self.traces: dict[str, list[np.ndarray]] = {leg: [] for leg in LEGS}
        self._swinging: set[str] = set()

    def __contains__(self, name: str) -> bool:
        return name in self.overlays

    # ------------------------------------------------------------------ drawing

    def draw(self, scene: mujoco.MjvScene, loop: ControlLoop) -> int:
        """Append this tick's overlay geoms to ``scene``; returns how many were added.

        Call it after the scene is filled from the model (``update_scene``, or on the
        viewer's empty ``user_scn`` after setting its ``ngeom`` to 0). Geoms beyond the
        scene's ``maxgeom`` are left out. Each call also extends the raised foot's trace
        (a point every 5 mm of its target's travel), so call it at a frame rate.
        """
        start = scene.ngeom
        controller = loop.controller
        if "polygon" in self.overlays:
            self._draw_polygon(scene, loop)
        if "com" in self.overlays:
            self._draw_com(scene, controller.com_position())
        if "forces" in self.overlays and loop.last_output is not None:
            self._draw_forces(scene, loop, loop.last_output.forces, FORCE_RGBA, width=0.015,
                              offset_m=0.0)
        from sim.control_loop import SimulatedLoop  # loaded with the loop already

        if "measured" in self.overlays and isinstance(loop, SimulatedLoop):
            measured = loop.sim.foot_contact_force_array()
            self._draw_forces(scene, loop, measured, MEASURED_RGBA, width=0.007,
                              offset_m=0.035)
        if "target" in self.overlays:
            swing = [leg for leg in LEGS if leg not in controller.stance_legs]
            self._record_traces(controller, swing)
            for leg in swing:
                self._draw_target(scene, leg, controller.foot_target(leg))
        if "gait" in self.overlays:
            view = self.gait_view(loop)
            if view is not None:
                self.gait.draw(scene, view)
                self.gait_shown = True
        return scene.ngeom - start

    def gait_view(self, loop: ControlLoop) -> GaitView | None:
        """The walking motion's view at the controller's state (``None``: nothing walks)."""
        source = self.gait_of(loop)
        if source is None:
            return None
        return GaitView.of(source, q=loop.context.q, feet=loop.controller.foot_positions())

    def _draw_com(self, scene: mujoco.MjvScene, com: np.ndarray) -> None:
        import mujoco

        ground = np.array([com[0], com[1], FLOOR_Z])
        add_geom(scene, mujoco.mjtGeom.mjGEOM_SPHERE, COM_RGBA, size=(0.025, 0, 0), pos=com)
        add_geom(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, COM_RGBA, size=(0.022, 0.001, 0),
             pos=ground)
        connect(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, COM_RGBA, 0.003, com, ground)

    def _draw_polygon(self, scene: mujoco.MjvScene, loop: ControlLoop) -> None:
        import mujoco

        controller = loop.controller
        legs = controller.support_legs()
        if len(legs) < 3:  # no polygon (the controller then has no support constraint)
            return
        corners = SupportPolygon.ordered(np.array([controller.foot_position(leg)
                                                   for leg in legs]))
        ring = on_floor(corners)
        centre = ring.mean(axis=0)
        for a, b in zip(ring, np.roll(ring, -1, axis=0)):
            connect(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, POLYGON_RGBA, 0.006, a, b)
            triangle(scene, POLYGON_FILL_RGBA, centre, a, b)
        contacts = getattr(getattr(controller, "config", None), "contacts", None)
        margin = float(getattr(contacts, "support_margin_m", 0.0))
        inner = SupportPolygon(margin_m=margin).inset(corners)
        if inner is not None:
            inner_ring = on_floor(inner, z=FLOOR_Z + 0.001)
            for a, b in zip(inner_ring, np.roll(inner_ring, -1, axis=0)):
                connect(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, MARGIN_RGBA, 0.003, a, b)

    def _draw_forces(self, scene: mujoco.MjvScene, loop: ControlLoop, forces: np.ndarray,
                     rgba: Sequence[float], *, width: float, offset_m: float) -> None:
        import mujoco

        controller = loop.controller
        com = controller.com_position()
        for i, leg in enumerate(LEGS):
            force = forces[i]
            if not np.isfinite(force).all() or force @ force < 1.0:
                continue
            start = controller.foot_position(leg)
            start[2] -= FOOT_RADIUS_M  # the contact point, where the force acts
            if offset_m:  # beside the commanded arrow, away from the body
                out = start[:2] - com[:2]
                start[:2] += offset_m * out / max(float(np.hypot(*out)), 1e-9)
            connect(scene, mujoco.mjtGeom.mjGEOM_ARROW, rgba, width, start,
                     start + self.force_scale_m_per_n / ARROW_DRAWN_FRACTION * force)

    def _draw_target(self, scene: mujoco.MjvScene, leg: str, target: np.ndarray | None) -> None:
        import mujoco

        if target is None:
            return
        # Larger than the foot, which covers it while tracking well: a halo around the foot.
        add_geom(scene, mujoco.mjtGeom.mjGEOM_SPHERE, TARGET_RGBA,
             size=(1.5 * FOOT_RADIUS_M, 0, 0), pos=target)
        trace = self.traces[leg]
        for a, b in itertools.pairwise(trace):
            connect(scene, mujoco.mjtGeom.mjGEOM_LINE, TRACE_RGBA, 3.0, a, b)

    def _record_traces(self, controller: object, swing: list[str]) -> None:
        for leg in swing:
            trace = self.traces[leg]
            if leg not in self._swinging:  # a new lift: a new trace
                trace.clear()
            target = controller.foot_target(leg)
            if target is not None and (not trace or np.linalg.norm(target - trace[-1])
                                       >= _TRACE_STEP_M):
                trace.append(target)
                del trace[:-_TRACE_POINTS]
        self._swinging = set(swing)

    # ------------------------------------------------------------------ text

    def legend(self) -> list[tuple[str, tuple[float, ...], str]]:
        """What each colour drawn shows: ``(colour name, RGBA, text)`` per colour, for the
        overlays that are on, in drawing order (:data:`LEGEND`); the force arrows' text
        gives their scale."""
        entries = []
        for name in OVERLAY_NAMES:
            if name not in self.overlays:
                continue
            for colour, rgba, text in LEGEND.get(name, ()):
                if name in ("forces", "measured"):  # no commas: the viewer's font lacks them
                    text += f" ({self.force_scale_m_per_n * 1e3:g} mm/N)"
                entries.append((colour, tuple(rgba), text))
            if name == "gait" and self.gait_shown:
                entries += [(c, tuple(rgba), text) for c, rgba, text in self.gait.legend()]
        return entries

    def legend_lines(self) -> tuple[str, str]:
        """:meth:`legend` as the viewer's two text columns: colour names and what they show."""
        entries = self.legend()
        return ("\n".join(e[0] for e in entries), "\n".join(e[2] for e in entries))

    def caption(self, loop: ControlLoop) -> str:
        """One line for a video frame: the goal's phase and progress, and the time."""
        text = f"t {loop.context.now_s:5.2f} s"
        if self.status_of is not None:
            phase, progress = self.status_of()
            text = f"{phase or '-'}  {100.0 * progress:3.0f} %   " + text
        return text

    def draw_caption(self, scene: mujoco.MjvScene, loop: ControlLoop, *, aspect: float) -> None:
        """:meth:`caption` as a label at the top left of the view of ``scene``'s camera.

        Call it after ``update_scene``, which sets the camera. A label is text MuJoCo draws
        above and to the right of a 3D point, so the point is put 60 cm in front of the
        camera (MuJoCo leaves out labels nearer than about 40 cm; the robot the camera
        tracks is farther), near the view's top left corner.

        Args:
            scene: The scene to add the label to.
            loop: The control loop whose state the caption tells.
            aspect: The image's width over its height (MuJoCo's perspective camera leaves
                its frustum's width to the viewport).
        """
        import mujoco

        geom = next_geom(scene)
        if geom is None:
            return
        camera = scene.camera[0]
        forward, up = np.array(camera.forward), np.array(camera.up)
        right = np.cross(forward, up)
        # One camera per eye, either side of the head; a mono view is from their average.
        head = (np.array(scene.camera[0].pos) + np.array(scene.camera[1].pos)) / 2
        near = camera.frustum_near
        half_height = 0.5 * (camera.frustum_top - camera.frustum_bottom)
        half_width = camera.frustum_width or half_height * aspect
        # Nearer the left edge MuJoCo drops the label altogether (about 0.9 of the half width).
        x = camera.frustum_center - 0.8 * half_width
        y = camera.frustum_top - 0.25 * half_height
        depth = 0.6
        pos = head + depth * forward + depth / near * (x * right + y * up)
        init_geom(geom, mujoco.mjtGeom.mjGEOM_LABEL, (1.0, 1.0, 1.0, 1.0), ZERO3, pos)
        geom.label = self.caption(loop)

    def status_lines(self, loop: ControlLoop) -> tuple[str, str]:
        """The text panel: names and values, one per line (the viewer's two columns)."""
        rows: list[tuple[str, str]] = []
        if self.status_of is not None:
            phase, progress = self.status_of()
            rows += [("phase", phase or "-"), ("progress", f"{100.0 * progress:.0f} %")]
        rows.append(("time", f"{loop.context.now_s:.2f} s"))
        controller = loop.controller
        rows.append(("support", " ".join(controller.support_legs()) or "-"))
        view = self.gait_view(loop) if "gait" in self.overlays else None
        if view is not None:
            rows.append(("swing", " ".join(view.swing_legs) or "-"))
            for label, values in (("commanded", view.commanded), ("measured", view.measured)):
                rows.append((label, "  ".join(f"{value:+.2f} {unit}" for value, unit
                                              in zip(values, VELOCITY_UNITS, strict=True))))
        margin = loop.context.com_margin_m()
        if math.isfinite(margin):
            rows.append(("CoM margin", f"{margin * 1e3:.0f} mm"))
        out = loop.last_output
        if out is not None and np.isfinite(out.forces).all():
            rows.append(("normal force", "  ".join(
                f"{leg} {out.forces[i, 2]:.0f}" for i, leg in enumerate(LEGS)) + " N"))
        return "\n".join(r[0] for r in rows), "\n".join(r[1] for r in rows)
