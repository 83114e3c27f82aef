"""Decor geoms appended to a MuJoCo scene: shapes, connectors, triangles (the overlays' pen)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import mujoco

# MuJoCo is imported where it is used: the command line parses --overlay before it chooses
# MuJoCo's rendering backend (MUJOCO_GL), which must precede the import.

#: Height [m] of the floor drawings above the floor, enough to win the depth test.
FLOOR_Z = 0.003
IDENTITY = np.eye(3).reshape(9)
ZERO3 = np.zeros(3)
#: The share of an arrow geom's ``size[2]`` MuJoCo 4.0's renderer draws: the shaft and head
#: span half of it (``tests/test_scene_overlay.py`` checks the drawn length in pixels).
ARROW_DRAWN_FRACTION = 0.5


def on_floor(points: np.ndarray, z: float = FLOOR_Z) -> np.ndarray:
    """``points`` (N, 2 or 3) [m] at height ``z`` [m]: a ring drawn on the floor."""
    ring = np.empty((len(points), 3))
    ring[:, :2] = points[:, :2]
    ring[:, 2] = z
    return ring


def next_geom(scene: mujoco.MjvScene) -> mujoco.MjvGeom | None:
    """The scene's next free geom, counted in; ``None`` when the scene is full."""
    if scene.ngeom >= scene.maxgeom:
        return None
    geom = scene.geoms[scene.ngeom]
    scene.ngeom += 1
    return geom


def init_geom(geom: mujoco.MjvGeom, kind: int, rgba: Sequence[float], size: Sequence[float],
              pos: np.ndarray, mat: np.ndarray = IDENTITY) -> None:
    """Make ``geom`` a decor geom of ``kind``: no physics, no shadow, lit a little from within."""
    import mujoco

    mujoco.mjv_initGeom(geom, kind, np.asarray(size, dtype=float), np.asarray(pos, dtype=float),
                        mat, np.asarray(rgba, dtype=np.float32))
    geom.category = mujoco.mjtCatBit.mjCAT_DECOR
    geom.castshadow = False
    geom.emission = 0.35  # keeps the hue under the lights, for people and for tests


def add_geom(scene: mujoco.MjvScene, kind: int, rgba: Sequence[float], *,
             size: Sequence[float], pos: np.ndarray) -> None:
    """Append a geom of ``kind`` and ``size`` [m] at ``pos`` [m] (nothing when full)."""
    geom = next_geom(scene)
    if geom is not None:
        init_geom(geom, kind, rgba, size, pos)


def connect(scene: mujoco.MjvScene, kind: int, rgba: Sequence[float], width: float,
            start: np.ndarray, end: np.ndarray) -> None:
    """Append a connector of ``kind`` (capsule, arrow, line) from ``start`` to ``end`` [m]."""
    import mujoco

    geom = next_geom(scene)
    if geom is not None:
        init_geom(geom, kind, rgba, ZERO3, ZERO3)
        mujoco.mjv_connector(geom, kind, width, np.asarray(start, dtype=float),
                             np.asarray(end, dtype=float))


def arrow(scene: mujoco.MjvScene, rgba: Sequence[float], width: float, start: np.ndarray,
          end: np.ndarray) -> None:
    """Append an arrow drawn from ``start`` to ``end`` [m] (its geom made
    1 / :data:`ARROW_DRAWN_FRACTION` as long, since the renderer draws that share of it)."""
    import mujoco

    start = np.asarray(start, dtype=float)
    connect(scene, mujoco.mjtGeom.mjGEOM_ARROW, rgba, width, start,
            start + (np.asarray(end, dtype=float) - start) / ARROW_DRAWN_FRACTION)


def triangle(scene: mujoco.MjvScene, rgba: Sequence[float], a: np.ndarray, b: np.ndarray,
             c: np.ndarray) -> None:
    """A filled triangle: MuJoCo's triangle spans (0, 0, 0), (size0, 0, 0), (0, size1, 0) of
    its frame, so a frame whose axes are the two edges (and the normal) maps it onto a b c."""
    import mujoco

    geom = next_geom(scene)
    if geom is None:
        return
    u, v = b - a, c - a
    normal = np.cross(u, v)
    length = float(np.linalg.norm(normal))
    if length < 1e-12:
        scene.ngeom -= 1
        return
    if normal[2] < 0:  # face up, towards the light
        u, v, normal = v, u, -normal
    mat = np.column_stack([u, v, normal / length]).reshape(9)
    init_geom(geom, mujoco.mjtGeom.mjGEOM_TRIANGLE, rgba, (1.0, 1.0, 1.0), a, mat)
