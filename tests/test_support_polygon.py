"""The support polygon: the compiled shrunk-polygon distance agrees with the half-planes."""

import numpy as np
import pytest

from wbc.model.support_polygon import MAX_CORNERS, SupportPolygon, shrunk_signed_distance

#: Feet of a standing GO2 [m], roughly: the corners of the support polygons below.
STANCE = np.array([[0.19, 0.14], [0.19, -0.14], [-0.19, 0.14], [-0.19, -0.14]])


def test_shrunk_distance_is_the_signed_distance_of_the_shrunk_corners():
    rng = np.random.default_rng(21)
    inside = outside = 0
    for _ in range(2000):
        k = int(rng.integers(3, 5))
        points = STANCE[rng.permutation(4)[:k]] + rng.normal(scale=0.01, size=(k, 2))
        point = rng.normal(scale=0.15, size=2)
        shrink = rng.uniform(0.3, 1.0) if rng.random() < 0.8 else 1.0
        centre = points.mean(axis=0)
        expected = SupportPolygon.signed_distance(centre + shrink * (points - centre), point)
        got = shrunk_signed_distance(points, point, shrink=shrink)
        assert got == pytest.approx(expected, abs=1e-15)
        inside += expected > 0.0
        outside += expected < 0.0
    assert inside > 200 and outside > 200


def test_rows_beyond_count_are_ignored_and_any_array_like_works():
    feet = np.zeros((4, 3))
    feet[:3, :2] = STANCE[:3]
    feet[3] = 100.0  # not a corner
    point = np.array([0.05, 0.05, 0.3])
    expected = SupportPolygon.signed_distance(STANCE[:3], point)
    assert shrunk_signed_distance(feet, point, count=3) == pytest.approx(expected, abs=1e-15)
    assert shrunk_signed_distance(STANCE[:3].tolist(), [0.05, 0.05]) == pytest.approx(
        expected, abs=1e-15)
    assert shrunk_signed_distance(STANCE, (0.0, 0.0)) == pytest.approx(0.14)
    assert shrunk_signed_distance(STANCE, (0.0, 0.0), shrink=0.5) == pytest.approx(0.07)


@pytest.mark.parametrize("count", [2, MAX_CORNERS + 1])
def test_corner_count_is_checked(count):
    points = np.zeros((MAX_CORNERS + 1, 2))
    with pytest.raises(ValueError, match=f"count: expected 3 to {MAX_CORNERS} corners"):
        shrunk_signed_distance(points, (0.0, 0.0), count=count)


def test_the_margin_moves_every_edge_inwards():
    square = np.array([[0.2, 0.1], [-0.2, 0.1], [-0.2, -0.1], [0.2, -0.1]])
    inner = SupportPolygon(margin_m=0.015).inset(square)
    expected = [[0.185, 0.085], [-0.185, 0.085], [-0.185, -0.085], [0.185, -0.085]]
    assert sorted(map(tuple, inner.round(12))) == sorted(map(tuple, np.round(expected, 12)))
    # Nothing is left of a 0.2 m wide polygon.
    assert SupportPolygon(margin_m=0.11).inset(square) is None


def test_closest_inside_is_the_nearest_point_of_the_inset_polygon():
    """Against brute force: the answer lies in the inset polygon, and no point sampled on
    the inset polygon's edges (where the nearest point of a convex polygon to an outside
    point lies) is nearer; a point already inside comes back unchanged."""
    rng = np.random.default_rng(5)
    polygon = SupportPolygon(margin_m=0.03)
    steps = np.linspace(0.0, 1.0, 2001)[:, None]
    moved = kept = 0
    for _ in range(300):
        k = int(rng.integers(3, 5))
        points = STANCE[rng.permutation(4)[:k]] + rng.normal(scale=0.01, size=(k, 2))
        point = rng.normal(scale=0.12, size=2)
        got = polygon.closest_inside(points, point)
        corners = polygon.inset(points)
        normals, offsets = polygon.halfplanes(points)
        assert (normals @ got - offsets >= -1e-12).all()
        if (normals @ point - offsets >= 0.0).all():
            assert np.array_equal(got, point)
            kept += 1
            continue
        moved += 1
        edges = [a + steps * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0))]
        nearest = np.linalg.norm(np.vstack(edges) - point, axis=1).min()
        assert np.linalg.norm(got - point) <= nearest + 1e-12
        assert np.linalg.norm(got - point) >= nearest - 1e-3 * 0.5  # sampled every 0.5 mm
    assert moved > 100 and kept > 20
