"""Support polygon of the stance feet: half-planes, signed margins, and safe points inside."""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.core.validation import as_float

#: Most corners a polygon given to :func:`shrunk_signed_distance` may have.
MAX_CORNERS = 8


@numba.njit(numba.float64(numba.float64[:, :], numba.int64, numba.float64, numba.float64,
                          numba.float64), cache=True, error_model="numpy")
def _shrunk_signed_distance(points, count, x, y, shrink):
    """:func:`shrunk_signed_distance` on the first ``count`` rows of ``points``."""
    cx = 0.0
    cy = 0.0
    for i in range(count):
        cx += points[i, 0]
        cy += points[i, 1]
    cx /= count
    cy /= count
    px = np.empty(MAX_CORNERS)
    py = np.empty(MAX_CORNERS)
    angle = np.empty(MAX_CORNERS)
    for i in range(count):
        if shrink == 1.0:
            px[i], py[i] = points[i, 0], points[i, 1]
        else:
            px[i] = cx + shrink * (points[i, 0] - cx)
            py[i] = cy + shrink * (points[i, 1] - cy)
    # Counter-clockwise around the shrunk points' centroid (as SupportPolygon.ordered).
    sx = 0.0
    sy = 0.0
    for i in range(count):
        sx += px[i]
        sy += py[i]
    sx /= count
    sy /= count
    for i in range(count):
        angle[i] = math.atan2(py[i] - sy, px[i] - sx)
    for i in range(1, count):  # insertion sort: a handful of corners
        a, u, w = angle[i], px[i], py[i]
        j = i - 1
        while j >= 0 and angle[j] > a:
            angle[j + 1], px[j + 1], py[j + 1] = angle[j], px[j], py[j]
            j -= 1
        angle[j + 1], px[j + 1], py[j + 1] = a, u, w
    distance = math.inf
    for i in range(count):  # inward unit normal of edge i, as SupportPolygon.halfplanes
        j = (i + 1) % count
        nx = -(py[j] - py[i])
        ny = px[j] - px[i]
        norm = math.sqrt(nx * nx + ny * ny)
        nx /= norm
        ny /= norm
        distance = min(distance, nx * x + ny * y - (nx * px[i] + ny * py[i]))
    return distance


def shrunk_signed_distance(points: np.ndarray, point: np.ndarray, *, shrink: float = 1.0,
                           count: int | None = None) -> float:
    """Signed distance [m] from ``point`` to the polygon of ``points`` shrunk about their centroid.

    The polygon's corners are ``centre + shrink (points - centre)``; the distance is to its
    nearest edge, positive inside (:meth:`SupportPolygon.signed_distance` of those corners,
    to rounding). One compiled call (about 1 us for a float64 ``points`` array, where the
    NumPy half-planes take tens): a control loop can call it every tick.

    Args:
        points: Corners (k, 2) or (k, 3) [m] in any order (only x and y are used), at least 3
            and at most :data:`MAX_CORNERS`.
        point: The point (2,) or (3,) [m]; only x and y are used.
        shrink: Scale of the polygon about its centroid (1: the polygon itself).
        count: Use only the first ``count`` rows of ``points`` (all by default).

    Raises:
        ValueError: Fewer than 3 or more than :data:`MAX_CORNERS` corners.
    """
    if count is None:
        count = len(points)
    if not 3 <= count <= MAX_CORNERS or count > len(points):
        raise ValueError(f"count: expected 3 to {MAX_CORNERS} corners (at most the "
                         f"{len(points)} rows of points), received {count}")
    x, y = float(point[0]), float(point[1])
    try:
        return _shrunk_signed_distance(points, count, x, y, float(shrink))
    except TypeError:  # not a float64 matrix
        points = np.asarray(points, dtype=np.float64)
        return _shrunk_signed_distance(points, count, x, y, float(shrink))


@numba.njit(cache=True)
def capture_point_margin(feet, support, com, com_velocity, shrink, gravity):  # pragma: no cover
    """Signed distance [m] of the capture point to the support polygon shrunk about its centroid.

    The capture point ``c + c_dot / omega0`` (``omega0 = sqrt(g / z_com)``, with ``z_com``
    at least 5 cm) is where the centre of mass would come to rest over. One compiled call,
    for a balance watch that runs every control tick.

    Args:
        feet: Foot positions (n, 3) [m].
        support: Indices (k,) of the rows of ``feet`` that make the polygon (3 to
            :data:`MAX_CORNERS`).
        com, com_velocity: Centre of mass [m] and its velocity [m/s] (3,).
        shrink: Scale of the polygon about its centroid (see :func:`shrunk_signed_distance`).
        gravity: [m/s^2].
    """
    count = support.size
    corners = np.empty((count, 2))
    for i in range(count):
        corners[i, 0] = feet[support[i], 0]
        corners[i, 1] = feet[support[i], 1]
    omega0 = math.sqrt(gravity / max(com[2], 0.05))
    return _shrunk_signed_distance(corners, count, com[0] + com_velocity[0] / omega0,
                                   com[1] + com_velocity[1] / omega0, shrink)


class SupportPolygon:
    """Convex polygon of foot positions in the ground plane, with an inner margin.

    A point ``c`` is inside with margin when ``normals @ c - offsets >= 0`` for every edge.
    """

    def __init__(self, *, margin_m: float = 0.0):
        """Args:
            margin_m: Distance [m] the point must keep from every edge.
        """
        self.margin_m = as_float("margin_m", margin_m, low=0.0)

    @staticmethod
    def ordered(points: np.ndarray) -> np.ndarray:
        """The points (k, 2) in counter-clockwise order around their centroid."""
        points = np.asarray(points, dtype=float)[:, :2]
        centre = points.mean(axis=0)
        angles = np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0])
        return points[np.argsort(angles)]

    def halfplanes(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Inward unit normals (k, 2) and offsets (k,) of the polygon's edges, margin included."""
        corners = self.ordered(points)
        edges = np.roll(corners, -1, axis=0) - corners
        normals = np.column_stack([-edges[:, 1], edges[:, 0]])
        normals /= np.linalg.norm(normals, axis=1, keepdims=True)
        offsets = np.einsum("ij,ij->i", normals, corners) + self.margin_m
        return normals, offsets

    @staticmethod
    def signed_distance(points: np.ndarray, point: np.ndarray) -> float:
        """Distance [m] from ``point`` to the nearest edge: positive inside, negative outside."""
        normals, offsets = SupportPolygon(margin_m=0.0).halfplanes(points)
        return float(np.min(normals @ np.asarray(point, dtype=float)[:2] - offsets))

    def inset(self, points: np.ndarray) -> np.ndarray | None:
        """The polygon shrunk by the margin: every edge moved ``margin_m`` inwards.

        Returns its corners (k, 2) counter-clockwise (corner ``j`` where the inset edges
        ``j - 1`` and ``j`` meet), or ``None`` when the margin leaves nothing of it.
        """
        corners = _inset_corners(*self.halfplanes(points))
        return None if corners is None else np.array(corners)

    def closest_inside(self, points: np.ndarray, point: np.ndarray) -> np.ndarray:
        """The point of the polygon shrunk by the margin that is closest to ``point`` (2,).

        On Python floats: a handful of corners, where NumPy's per-call cost was most of the
        time (about 100 us a call, on the first tick of every leg lift).

        Raises:
            ValueError: The margin leaves nothing of the polygon.
        """
        point = np.asarray(point, dtype=float)[:2]
        normals, offsets = self.halfplanes(points)
        x, y = float(point[0]), float(point[1])
        if all(nx * x + ny * y - o >= 0.0
               for (nx, ny), o in zip(normals.tolist(), offsets.tolist())):
            return point.copy()
        corners = _inset_corners(normals, offsets)
        if corners is None:
            raise ValueError(f"margin {self.margin_m} m leaves nothing of the support polygon")
        best, best_distance = corners[0], math.inf
        for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1]):  # inset edges
            ex, ey = bx - ax, by - ay
            t = min(max(((x - ax) * ex + (y - ay) * ey) / max(ex * ex + ey * ey, 1e-18), 0.0),
                    1.0)
            candidate = (ax + t * ex, ay + t * ey)
            distance = math.hypot(candidate[0] - x, candidate[1] - y)
            if distance < best_distance:
                best, best_distance = candidate, distance
        return np.array(best)


def _inset_corners(normals: np.ndarray, offsets: np.ndarray
                   ) -> list[tuple[float, float]] | None:
    """Where consecutive half-plane edges meet (corner ``j``: edges ``j - 1`` and ``j``),
    counter-clockwise; ``None`` when two are parallel or a corner lies outside another
    half-plane (nothing is left of the polygon)."""
    rows = normals.tolist()
    levels = offsets.tolist()
    k = len(rows)
    corners: list[tuple[float, float]] = [(0.0, 0.0)] * k
    for i in range(k):
        j = (i + 1) % k
        (a, b), (c, d) = rows[i], rows[j]
        det = a * d - b * c
        if abs(det) < 1e-12:
            return None
        corners[j] = ((levels[i] * d - b * levels[j]) / det, (a * levels[j] - c * levels[i]) / det)
    for (nx, ny), level in zip(rows, levels):
        if any(nx * cx + ny * cy - level < -1e-9 for cx, cy in corners):
            return None
    return corners
