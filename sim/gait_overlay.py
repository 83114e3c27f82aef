"""The gait drawn into a MuJoCo scene from a :class:`sim.gait_view.GaitView`: stance and swing
feet, planned footholds, the commanded and the measured velocity."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from sim.scene_geoms import FLOOR_Z, add_geom, arrow, connect
from wbc.core.validation import as_float
from wbc.model.description import FOOT_RADIUS_M, LEGS

if TYPE_CHECKING:
    import mujoco

    from sim.gait_view import GaitView

# MuJoCo is imported where it is used: the command line parses --overlay before it chooses
# MuJoCo's rendering backend (MUJOCO_GL), which must precede the import.

#: Colours (RGBA): hues the other overlays and the scene do not use, dark enough that the
#: scene's lights do not saturate a channel and shift the hue (a violet of (0.55, 0.25, 1.0)
#: rendered as magenta).
STANCE_RGBA = (0.00, 0.85, 0.85, 1.0)
SWING_RGBA = (0.35, 0.10, 0.70, 1.0)
#: Opaque: a translucent disc takes the floor's hue under the lights.
FOOTHOLD_RGBA = SWING_RGBA
COMMANDED_RGBA = (0.75, 0.15, 0.35, 1.0)
MEASURED_VELOCITY_RGBA = (0.40, 0.70, 0.00, 1.0)
#: The velocity arrows show where the base would be this long [s] ahead at that velocity:
#: 1 m/s is a 1 m arrow, 1 rad/s an arc of 1 rad.
VELOCITY_HORIZON_S = 1.0
#: Height [m] of the velocity arrows above the base's origin (over the body, clear of it).
ARROW_HEIGHT_M = 0.15
#: Radius [m] of the yaw-rate arcs around the base's vertical (the measured one outside).
ARC_RADIUS_M = 0.25
#: Largest arc drawn [rad] (a faster turn reads as a near circle).
_ARC_MAX_RAD = 1.8 * math.pi
#: Radius [m] of a stance foot's disc on the floor, of a foothold's disc.
STANCE_DISC_M, FOOTHOLD_DISC_M = 0.045, 0.035
#: Arrows and arcs shorter than this [m] are left out (a zero command draws nothing).
_MIN_LENGTH_M = 0.005


def gait_legend(horizon_s: float = VELOCITY_HORIZON_S) -> tuple[
        tuple[str, tuple[float, ...], str], ...]:
    """``(colour name, RGBA, text)`` per colour the gait overlay draws (no commas in the
    texts: the viewer's font lacks them)."""
    ahead = f"{horizon_s:g} s ahead"
    return (("cyan", STANCE_RGBA, "feet in stance"),
            ("violet", SWING_RGBA, "feet in swing and their planned footholds"),
            ("pink", COMMANDED_RGBA, f"commanded velocity and yaw rate ({ahead})"),
            ("lime", MEASURED_VELOCITY_RGBA, f"measured velocity and yaw rate ({ahead})"))


class GaitOverlay:
    """Draws a :class:`~sim.gait_view.GaitView`:

    - each stance foot: a cyan disc on the floor under it;
    - each swing foot: a violet ball around it, a thin violet line from it to its planned
      foothold and a violet disc on the floor there;
    - the commanded velocity (pink) and the measured one (lime, thinner, a little higher):
      an arrow from above the base to where the base would be :attr:`horizon_s` ahead, and
      an arc around the base's vertical through the heading it would turn by in that time,
      its last segment an arrowhead.

    Args:
        horizon_s: How far ahead [s] the arrows reach (their scale: metres per m/s).

    Raises:
        ConfigurationError: A horizon that is not positive.
    """

    def __init__(self, *, horizon_s: float = VELOCITY_HORIZON_S):
        self.horizon_s = as_float("horizon_s", horizon_s, low=1e-3)

    def legend(self) -> tuple[tuple[str, tuple[float, ...], str], ...]:
        """What each colour shows (:func:`gait_legend`)."""
        return gait_legend(self.horizon_s)

    def draw(self, scene: mujoco.MjvScene, view: GaitView) -> int:
        """Append the view's geoms to ``scene`` (nothing beyond its ``maxgeom``); returns how
        many were added."""
        import mujoco

        start = scene.ngeom
        for i, leg in enumerate(LEGS):
            foot = view.feet[i]
            if leg in view.stance_legs:
                add_geom(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, STANCE_RGBA,
                         size=(STANCE_DISC_M, 0.001, 0), pos=np.array([*foot[:2], FLOOR_Z]))
                continue
            add_geom(scene, mujoco.mjtGeom.mjGEOM_SPHERE, SWING_RGBA,
                     size=(1.3 * FOOT_RADIUS_M, 0, 0), pos=foot)
            foothold = view.footholds.get(leg)
            if foothold is not None:
                ground = np.array([foothold[0], foothold[1], FLOOR_Z + 0.001])
                add_geom(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, FOOTHOLD_RGBA,
                         size=(FOOTHOLD_DISC_M, 0.001, 0), pos=ground)
                connect(scene, mujoco.mjtGeom.mjGEOM_LINE, SWING_RGBA, 2.0, foot, ground)
        origin = view.base_position + np.array([0.0, 0.0, ARROW_HEIGHT_M])
        for which, rgba, width, lift, radius in (
                ("commanded", COMMANDED_RGBA, 0.012, 0.0, ARC_RADIUS_M),
                ("measured", MEASURED_VELOCITY_RGBA, 0.007, 0.02, ARC_RADIUS_M + 0.03)):
            base = origin + np.array([0.0, 0.0, lift])
            reach = view.world_velocity(which) * self.horizon_s
            if float(np.hypot(reach[0], reach[1])) >= _MIN_LENGTH_M:
                arrow(scene, rgba, width, base, base + reach)
            yaw_rate = float((view.commanded if which == "commanded" else view.measured)[2])
            self._arc(scene, rgba, width, base, radius, view.heading_rad,
                      yaw_rate * self.horizon_s)
        return scene.ngeom - start

    @staticmethod
    def arc_points(centre: np.ndarray, radius_m: float, heading_rad: float,
                   turn_rad: float) -> np.ndarray:
        """Points (n, 3) [m] of an arc of ``radius_m`` around ``centre``'s vertical, from the
        heading ``heading_rad`` through ``turn_rad`` (positive: counter-clockwise, seen from
        above; capped at 1.8 pi), about 0.15 rad apart."""
        turn = max(-_ARC_MAX_RAD, min(_ARC_MAX_RAD, turn_rad))
        count = max(2, math.ceil(abs(turn) / 0.15) + 1)
        angles = heading_rad + np.linspace(0.0, turn, count)
        return np.column_stack([centre[0] + radius_m * np.cos(angles),
                                centre[1] + radius_m * np.sin(angles),
                                np.full(count, centre[2])])

    def _arc(self, scene: mujoco.MjvScene, rgba: Sequence[float], width: float,
             centre: np.ndarray, radius_m: float, heading: float, turn: float) -> None:
        import mujoco

        if abs(turn) * radius_m < _MIN_LENGTH_M:
            return
        points = self.arc_points(centre, radius_m, heading, turn)
        for a, b in itertools.pairwise(points[:-1]):
            connect(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, rgba, 0.5 * width, a, b)
        arrow(scene, rgba, width, points[-2], points[-1])
