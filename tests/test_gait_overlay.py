"""The gait overlay: its plain-data view, the heading-frame velocities, and the geoms it draws
(where, in which colour, how long), from views built here (a walking frame's pixels are in
tests/test_walking_overlay.py)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from sim.gait_overlay import (
    ARC_RADIUS_M,
    ARROW_HEIGHT_M,
    COMMANDED_RGBA,
    FOOTHOLD_RGBA,
    MEASURED_VELOCITY_RGBA,
    STANCE_RGBA,
    SWING_RGBA,
    GaitOverlay,
    gait_legend,
)
from sim.gait_view import GaitSource, GaitView, heading_rad, heading_velocities
from sim.scene_geoms import ARROW_DRAWN_FRACTION, FLOOR_Z
from sim.scene_overlay import LEGEND, OVERLAY_NAMES, SceneOverlay, parse_overlays
from wbc.core.errors import ConfigurationError, NonFiniteError, UnknownNameError

FEET = np.array([[0.19, 0.14, 0.02], [0.19, -0.14, 0.08], [-0.19, 0.14, 0.07],
                 [-0.19, -0.14, 0.02]])


def yaw_quaternion(yaw: float) -> np.ndarray:
    """(x, y, z, w) of a turn by ``yaw`` [rad] about the vertical."""
    return np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)])


def configuration(yaw: float = 0.0, position=(0.3, -0.2, 0.3)) -> np.ndarray:
    q = np.zeros(19)
    q[:3], q[3:7] = position, yaw_quaternion(yaw)
    return q


class Trotting:
    """What a walking motion exposes (the GaitSource protocol): FR and RL in swing."""

    def __init__(self) -> None:
        self.swing_legs = ("RL", "FR")
        self.footholds = {"FR": np.array([0.30, -0.15, 0.02]),
                          "RL": np.array([-0.08, 0.15, 0.02])}
        self.commanded_velocity = np.array([0.5, 0.0, 0.8])
        self.measured_velocity = np.array([0.45, 0.05, 0.7])


def view(yaw: float = 0.0, source: object = None) -> GaitView:
    return GaitView.of(source or Trotting(), q=configuration(yaw), feet=FEET)


def scene(maxgeom: int = 200) -> mujoco.MjvScene:
    return mujoco.MjvScene(mujoco.MjModel.from_xml_string("<mujoco/>"), maxgeom=maxgeom)


def drawn(s: mujoco.MjvScene, rgba) -> list[mujoco.MjvGeom]:
    return [s.geoms[i] for i in range(s.ngeom)
            if np.allclose(s.geoms[i].rgba, rgba, atol=1e-6)]


def arrow_tip(geom: mujoco.MjvGeom) -> np.ndarray:
    """Where MuJoCo's renderer draws an arrow geom's tip."""
    axis = geom.mat.reshape(3, 3)[:, 2]
    return np.array(geom.pos) + ARROW_DRAWN_FRACTION * geom.size[2] * axis


# ----------------------------------------------------------------------------- the view


def test_the_view_sorts_the_legs_and_names_the_stance_ones():
    v = view()
    assert v.swing_legs == ("FR", "RL") and v.stance_legs == ("FL", "RR")
    assert isinstance(Trotting(), GaitSource)
    np.testing.assert_allclose(v.base_position, [0.3, -0.2, 0.3])
    assert v.heading_rad == pytest.approx(0.0)
    # Copies: the motion's arrays may change under a view already taken.
    source = Trotting()
    v = view(source=source)
    source.commanded_velocity[0] = 9.0
    assert v.commanded[0] == 0.5


def test_the_world_velocity_turns_with_the_heading():
    v = view(yaw=math.pi / 2)
    np.testing.assert_allclose(v.world_velocity("commanded"), [0.0, 0.5, 0.0], atol=1e-12)
    np.testing.assert_allclose(v.world_velocity("measured"), [-0.05, 0.45, 0.0], atol=1e-12)
    with pytest.raises(UnknownNameError, match="valid velocitys: commanded, measured"):
        v.world_velocity("target")


@pytest.mark.parametrize(("change", "error", "message"), [
    ({"swing_legs": ("FR", "XX")}, UnknownNameError,
     "unknown swing leg 'XX'; valid swing legs: FL, FR, RL, RR"),
    ({"feet": np.zeros((3, 3))}, ConfigurationError,
     (r"feet: expected a finite \(4, 3\) array \(rows FL, FR, RL, RR\), received shape "
      r"\(3, 3\)")),
    ({"footholds": {"FR": [0.1, 0.2]}}, ConfigurationError,
     r"footholds\[FR\]: expected an array of shape \(3,\), received shape \(2,\)"),
    ({"footholds": {"BL": [0.1, 0.2, 0.0]}}, UnknownNameError, "unknown foothold leg 'BL'"),
    ({"commanded": [0.5, math.nan, 0.0]}, NonFiniteError,
     r"commanded: non-finite value at index \[1\]"),
    ({"heading_rad": math.inf}, ConfigurationError,
     "heading_rad: expected a finite angle, received inf"),
])
def test_a_malformed_view_names_its_field(change, error, message):
    fields = {"swing_legs": ("FR",), "feet": FEET, "footholds": {},
              "base_position": np.zeros(3), "heading_rad": 0.0, "commanded": np.zeros(3),
              "measured": np.zeros(3)}
    with pytest.raises(error, match=message):
        GaitView(**{**fields, **change})


def test_a_source_without_the_protocol_s_attributes_is_named():
    class Lifting:
        def __init__(self) -> None:
            self.swing_legs, self.footholds = ("FR",), {}

    with pytest.raises(ConfigurationError, match="Lifting lacks commanded_velocity, "
                                                 "measured_velocity"):
        GaitView.of(Lifting(), q=configuration(), feet=FEET)


# ----------------------------------------------------------------------------- velocities


def test_heading_velocities_read_the_base_frame_in_the_heading_frame():
    rng = np.random.default_rng(3)
    q = np.tile(configuration(), (3, 1))
    v = np.zeros((3, 18))
    # Heading 90 deg: the base's own x axis is the world's y; 0.5 m/s along it is forward.
    q[0, 3:7] = yaw_quaternion(math.pi / 2)
    v[0, :3] = [0.5, 0.0, 0.0]
    # Heading -30 deg, pitched 10 deg nose down, moving 0.3 m/s along the world's x axis
    # and turning at 0.7 rad/s about the world's vertical.
    yaw, pitch = -math.pi / 6, math.radians(10)
    rotation = (np.array([[math.cos(yaw), -math.sin(yaw), 0], [math.sin(yaw), math.cos(yaw), 0],
                          [0, 0, 1]])
                @ np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0],
                            [-math.sin(pitch), 0, math.cos(pitch)]]))
    half = 0.5 * math.acos(max(-1.0, min(1.0, (np.trace(rotation) - 1) / 2)))
    axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]]) / (2 * math.sin(2 * half))
    q[1, 3:7] = [*(math.sin(half) * axis), math.cos(half)]
    v[1, :3] = rotation.T @ [0.3, 0.0, 0.0]
    v[1, 3:6] = rotation.T @ [0.0, 0.0, 0.7]
    # Any unit quaternion scaled: the same as unscaled.
    q[2, 3:7] = 3.0 * yaw_quaternion(0.4)
    v[2, :6] = rng.normal(size=6)
    out = heading_velocities(q, v)
    np.testing.assert_allclose(out[0], [0.5, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(out[1], [0.3 * math.cos(yaw), -0.3 * math.sin(yaw), 0.7],
                               atol=1e-12)
    assert heading_rad(q[1]) == pytest.approx(yaw)
    expected = [math.cos(0.4) * (math.cos(0.4) * v[2, 0] - math.sin(0.4) * v[2, 1])
                + math.sin(0.4) * (math.sin(0.4) * v[2, 0] + math.cos(0.4) * v[2, 1]),
                v[2, 1], v[2, 5]]
    np.testing.assert_allclose(out[2], expected, atol=1e-12)
    np.testing.assert_allclose(heading_velocities(q[1], v[1]), out[1])
    with pytest.raises(ConfigurationError, match=r"received shapes \(3, 19\) and \(2, 18\)"):
        heading_velocities(q, v[:2])


# ----------------------------------------------------------------------------- the geoms


def test_every_leg_foothold_and_velocity_is_drawn_where_it_belongs():
    s = scene()
    count = GaitOverlay().draw(s, view(yaw=math.pi / 2))
    assert count == s.ngeom
    # Stance feet: a disc on the floor under FL and RR.
    discs = drawn(s, STANCE_RGBA)
    assert len(discs) == 2
    for geom, row in zip(discs, (0, 3), strict=True):
        assert geom.type == mujoco.mjtGeom.mjGEOM_CYLINDER
        np.testing.assert_allclose(geom.pos, [*FEET[row, :2], FLOOR_Z])
    # Swing feet: a ball at FR and RL, and a line from each to its foothold's disc.
    balls = [g for g in drawn(s, SWING_RGBA) if g.type == mujoco.mjtGeom.mjGEOM_SPHERE]
    lines = [g for g in drawn(s, SWING_RGBA) if g.type == mujoco.mjtGeom.mjGEOM_LINE]
    np.testing.assert_allclose([g.pos for g in balls], FEET[[1, 2]])
    assert len(lines) == 2
    holds = [g for g in drawn(s, FOOTHOLD_RGBA) if g.type == mujoco.mjtGeom.mjGEOM_CYLINDER]
    np.testing.assert_allclose([g.pos[:2] for g in holds], [[0.30, -0.15], [-0.08, 0.15]])
    # The commanded velocity, heading 90 deg: 0.5 m/s forward is a 0.5 m arrow along +y,
    # from 15 cm above the base; its yaw rate an arc of 0.8 rad ending in an arrowhead.
    start = np.array([0.3, -0.2, 0.3 + ARROW_HEIGHT_M])
    pink = drawn(s, COMMANDED_RGBA)
    arrows = [g for g in pink if g.type == mujoco.mjtGeom.mjGEOM_ARROW]
    np.testing.assert_allclose(arrows[0].pos, start)
    np.testing.assert_allclose(arrow_tip(arrows[0]), start + [0.0, 0.5, 0.0], atol=1e-9)
    end = start + ARC_RADIUS_M * np.array([math.cos(math.pi / 2 + 0.8),
                                           math.sin(math.pi / 2 + 0.8), 0.0])
    np.testing.assert_allclose(arrow_tip(arrows[1]), end, atol=1e-9)
    assert len(pink) == len(GaitOverlay.arc_points(start, ARC_RADIUS_M, 0.0, 0.8)) - 2 + 2
    # The measured velocity: lime, 2 cm higher, (-0.05, 0.45) m ahead in the world.
    lime = [g for g in drawn(s, MEASURED_VELOCITY_RGBA) if g.type == mujoco.mjtGeom.mjGEOM_ARROW]
    np.testing.assert_allclose(arrow_tip(lime[0]), start + [-0.05, 0.45, 0.02], atol=1e-9)


def test_the_arc_turns_the_way_the_yaw_rate_does_and_is_capped():
    points = GaitOverlay.arc_points(np.zeros(3), 0.2, 0.0, -1.0)
    assert points[1, 1] < 0 and np.allclose(np.hypot(points[:, 0], points[:, 1]), 0.2)
    assert np.all(np.diff(np.arctan2(points[:, 1], points[:, 0])) < 0)
    full = GaitOverlay.arc_points(np.zeros(3), 0.2, 0.0, 50.0)
    last = np.arctan2(full[-1, 1], full[-1, 0]) % (2 * math.pi)
    assert last == pytest.approx(1.8 * math.pi)


def test_a_standing_walk_draws_feet_and_no_arrows():
    standing = Trotting()
    standing.swing_legs, standing.footholds = (), {}
    standing.commanded_velocity = np.zeros(3)
    standing.measured_velocity = np.array([0.001, 0.0, 0.002])  # under 5 mm a second
    s = scene()
    assert GaitOverlay().draw(s, view(source=standing)) == 4
    assert len(drawn(s, STANCE_RGBA)) == 4


def test_the_horizon_scales_the_arrows_and_must_be_positive():
    s = scene()
    GaitOverlay(horizon_s=0.5).draw(s, view())
    arrows = [g for g in drawn(s, COMMANDED_RGBA) if g.type == mujoco.mjtGeom.mjGEOM_ARROW]
    assert arrows[0].size[2] * ARROW_DRAWN_FRACTION == pytest.approx(0.25)
    with pytest.raises(ConfigurationError, match="horizon_s"):
        GaitOverlay(horizon_s=0.0)
    assert gait_legend(0.5)[2] == ("pink", COMMANDED_RGBA,
                                   "commanded velocity and yaw rate (0.5 s ahead)")


def test_a_full_scene_takes_what_fits():
    s = scene(maxgeom=3)
    assert GaitOverlay().draw(s, view()) == 3


# ----------------------------------------------------------------------------- in the overlay


def test_gait_is_an_overlay_whose_legend_appears_once_a_gait_was_drawn():
    assert OVERLAY_NAMES[-1] == "gait" and parse_overlays("gait,com") == ("com", "gait")
    assert "gait" not in LEGEND  # its rows are the gait overlay's own
    overlay = SceneOverlay(("com", "gait"), gait_of=lambda loop: None)
    assert [e[0] for e in overlay.legend()] == ["red"]
    overlay.gait_shown = True
    assert [e[0] for e in overlay.legend()] == ["red", "cyan", "violet", "pink", "lime"]
    assert [e[2] for e in overlay.legend()][1:] == [e[2] for e in gait_legend()]
    assert all("," not in e[2] for e in overlay.legend())  # the viewer's font has none
