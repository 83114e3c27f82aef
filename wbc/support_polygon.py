"""Support polygon of the stance feet: half-planes, signed margins, and safe points inside."""

from __future__ import annotations

import numpy as np

from wbc.validation import as_float


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

    def closest_inside(self, points: np.ndarray, point: np.ndarray) -> np.ndarray:
        """The point of the polygon shrunk by the margin that is closest to ``point`` (2,).

        Raises:
            ValueError: The margin leaves nothing of the polygon.
        """
        point = np.asarray(point, dtype=float)[:2]
        normals, offsets = self.halfplanes(points)
        if np.all(normals @ point - offsets >= 0.0):
            return point.copy()
        k = len(normals)
        # Corners of the shrunk polygon: intersections of consecutive inset edges.
        corners = []
        for i in range(k):
            j = (i + 1) % k
            corners.append(np.linalg.solve(np.vstack([normals[i], normals[j]]),
                                           [offsets[i], offsets[j]]))
        corners = np.array(corners)
        if np.any(normals @ corners.T - offsets[:, None] < -1e-9):
            raise ValueError(f"margin {self.margin_m} m leaves nothing of the support polygon")
        best, best_distance = corners[0], np.inf
        for i in range(k):
            a, b = corners[i - 1], corners[i]  # the inset edge i runs between these corners
            ab = b - a
            t = np.clip((point - a) @ ab / max(ab @ ab, 1e-18), 0.0, 1.0)
            candidate = a + t * ab
            distance = np.linalg.norm(candidate - point)
            if distance < best_distance:
                best, best_distance = candidate, distance
        return best
