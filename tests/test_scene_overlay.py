"""The overlays: names, geometry, and every one of them found in the pixels of a rendered frame."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import matplotlib.colors
import mujoco
import numpy as np
import pytest

from actions import HighFiveGoal
from sim.control_loop import ControlLoop
from sim.gait_overlay import (
    COMMANDED_RGBA,
    FOOTHOLD_RGBA,
    MEASURED_VELOCITY_RGBA,
    STANCE_RGBA,
    SWING_RGBA,
)
from sim.scene_overlay import (
    COM_RGBA,
    DEFAULT_OVERLAYS,
    FORCE_RGBA,
    FORCE_SCALE_M_PER_N,
    MARGIN_RGBA,
    MEASURED_RGBA,
    OVERLAY_NAMES,
    POLYGON_FILL_RGBA,
    POLYGON_RGBA,
    TARGET_RGBA,
    TRACE_RGBA,
    SceneOverlay,
    parse_overlays,
)
from sim.video_recorder import LEGEND_MIN_HEIGHT_PX, LegendStamp, VideoRecorder
from sim.viewer import ViewerHook
from tests.test_gait_overlay import Trotting
from wbc.core.errors import ConfigurationError
from wbc.model.description import FOOT_RADIUS_M, LEGS
from wbc.model.support_polygon import SupportPolygon

#: Simulated time [s] of the rendered frame: the high five's foot is rising (goal sent at 0).
FRAME_S = 2.6
WIDTH, HEIGHT = 480, 360


# ----------------------------------------------------------------------------- names


@pytest.mark.parametrize(("text", "names"), [
    ("com,polygon,forces,target,gait", DEFAULT_OVERLAYS),
    ("target, COM", ("com", "target")),
    ("forces,forces", ("forces",)),
    ("all", OVERLAY_NAMES),
    ("none", ()),
])
def test_overlay_lists_parse_in_drawing_order(text, names):
    assert parse_overlays(text) == names


@pytest.mark.parametrize("text", ["bogus", "com,bogus", "", "all,com"])
def test_a_bad_overlay_list_names_the_valid_ones(text):
    with pytest.raises(ConfigurationError) as err:
        parse_overlays(text)
    assert str(err.value) == ("expected a comma-separated list of com, polygon, forces, "
                              f"measured, target, gait, or all or none; received {text!r}")


def test_an_unknown_overlay_name_is_refused_by_the_constructor():
    with pytest.raises(ConfigurationError, match=r"unknown overlay 'cop'; valid overlays: "
                                                 r"com, polygon, forces, measured, target, "
                                                 r"gait$"):
        SceneOverlay(("com", "cop"))


# ----------------------------------------------------------------------------- a frame


@pytest.fixture(scope="module")
def raising(tmp_path_factory: pytest.TempPathFactory):
    """A loop FRAME_S into a high five, an overlay with every layer, and its trace so far."""
    loop = ControlLoop.simulated()
    status = {"phase": "", "progress": 0.0}

    def on_feedback(message):
        status["phase"], status["progress"] = message.feedback.phase, message.feedback.progress

    loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.4, hold_seconds=1),
                                             feedback_callback=on_feedback)
    overlay = SceneOverlay(OVERLAY_NAMES, status_of=lambda: (status["phase"],
                                                             status["progress"]))
    scratch = mujoco.MjvScene(loop.sim.model, maxgeom=2000)
    while loop.robot.time_s < FRAME_S - 1e-9:
        loop.spin_once()
        if loop.runner.tick_count % 33 == 0:  # the overlay draws (and traces) at 30 fps
            scratch.ngeom = 0
            overlay.draw(scratch, loop)
    return loop, overlay, status, tmp_path_factory.mktemp("frame")


def project(scene: mujoco.MjvScene, points: np.ndarray, width: int, height: int) -> np.ndarray:
    """Pixel (column, row) of world points (n, 3), by the camera of a scene just rendered.

    A scene holds a camera per eye, half the inter-pupillary distance either side of the
    head; a mono render looks from their average.
    """
    camera = scene.camera[0]
    forward, up = np.array(camera.forward), np.array(camera.up)
    right = np.cross(forward, up)
    head = (np.array(scene.camera[0].pos) + np.array(scene.camera[1].pos)) / 2
    relative = np.atleast_2d(points) - head
    depth = relative @ forward
    near = camera.frustum_near
    x = relative @ right * near / depth
    y = relative @ up * near / depth
    half_height = 0.5 * (camera.frustum_top - camera.frustum_bottom)
    half_width = camera.frustum_width or half_height * width / height
    column = (x - camera.frustum_center + half_width) / (2 * half_width) * width
    row = (camera.frustum_top - y) / (camera.frustum_top - camera.frustum_bottom) * height
    return np.column_stack([column, row])


def hue_mask(frame: np.ndarray, rgba, *, min_saturation: float = 0.5,
             min_value: float = 0.25) -> np.ndarray:
    """Pixels of the hue of ``rgba`` (within 0.03 of a turn), saturated and bright enough."""
    hsv = matplotlib.colors.rgb_to_hsv(frame / 255.0)
    hue = matplotlib.colors.rgb_to_hsv(np.array(rgba[:3]))[0]
    distance = np.abs((hsv[..., 0] - hue + 0.5) % 1.0 - 0.5)
    return (distance < 0.03) & (hsv[..., 1] >= min_saturation) & (hsv[..., 2] >= min_value)


def found(mask: np.ndarray, pixel: np.ndarray, radius: int = 2) -> bool:
    """Whether ``mask`` is set within ``radius`` pixels of ``pixel`` (column, row)."""
    column, row = (round(float(v)) for v in pixel)
    rows = slice(max(row - radius, 0), row + radius + 1)
    window = mask[rows, max(column - radius, 0):column + radius + 1]
    return bool(window.any())


@pytest.fixture(scope="module")
def frames(raising):
    """The frame with every overlay, the same frame without, and its scene's camera."""
    loop, overlay, _, folder = raising
    try:
        recorder = VideoRecorder(loop.sim, folder / "frame.mp4", fps=30, size=(WIDTH, HEIGHT),
                                 overlay=overlay)
    except Exception as err:  # noqa: BLE001 - GL backends fail in assorted types
        pytest.skip(f"no offscreen OpenGL on this machine: {' '.join(str(err).split())}")
    try:
        with_overlays = recorder.render(loop)
        scene = recorder.renderer.scene

        def pixel_of(points):
            return project(scene, np.asarray(points, float), WIDTH, HEIGHT)

        head = (np.array(scene.camera[0].pos) + np.array(scene.camera[1].pos)) / 2
        lookat = pixel_of(head + np.array(scene.camera[0].forward))
        recorder.overlay = None
        without = recorder.render(loop)
    finally:
        recorder.close()
    return with_overlays, without, pixel_of, lookat


def test_the_projection_puts_the_view_direction_at_the_image_centre(frames):
    *_, lookat = frames
    np.testing.assert_allclose(lookat[0], [WIDTH / 2, HEIGHT / 2], atol=1e-6)


def test_every_overlay_is_in_the_rendered_frame(raising, frames):
    loop, overlay, status, _ = raising
    frame, plain, pixel_of, _ = frames
    controller = loop.controller
    assert status["phase"] == "raising"
    assert controller.stance_legs == ["FL", "RL", "RR"]
    assert controller.support_legs() == ["FL", "RL", "RR"]
    feet = {leg: controller.foot_position(leg) for leg in LEGS}

    # The support polygon: its outline along each edge, its fill between the centre and
    # each foot, in green; the margin's outline, in yellow, along its edges (the legs hide
    # a little of them: most points suffice). Neither in the frame without overlays.
    polygon, fill = hue_mask(frame, POLYGON_RGBA), hue_mask(frame, POLYGON_RGBA,
                                                             min_saturation=0.25)
    corners = np.array([feet[leg] for leg in ("FL", "RL", "RR")])
    corners[:, 2] = 0.003
    inset = SupportPolygon(margin_m=controller.config.contacts.support_margin_m).inset(corners)
    inner = np.column_stack([inset, np.full(3, 0.004)])
    margin = hue_mask(frame, MARGIN_RGBA)
    along = np.linspace(0.2, 0.8, 7)[:, None]
    for i in range(3):
        j = (i + 1) % 3
        edge = pixel_of(corners[i] + along * (corners[j] - corners[i]))
        assert np.mean([found(polygon, p) for p in edge]) >= 0.7, f"edge {i}-{j}"
        edge = pixel_of(inner[i] + along * (inner[j] - inner[i]))
        assert np.mean([found(margin, p) for p in edge]) >= 0.7, f"margin edge {i}-{j}"
        centre = corners.mean(axis=0)
        inside = pixel_of(centre + 0.3 * (corners[i] - centre))[0]
        assert found(fill, inside, radius=1), f"fill towards corner {i}"
    assert not hue_mask(plain, POLYGON_RGBA).any() and not hue_mask(plain, MARGIN_RGBA).any()

    # The CoM: its vertical line below the body, and its projection on the floor, in red.
    com = controller.com_position()
    red = hue_mask(frame, COM_RGBA)
    assert found(red, pixel_of([com[0], com[1], 0.003])[0])
    assert found(red, pixel_of([com[0], com[1], 0.06])[0])

    # One orange arrow per stance foot from its contact point, as long as the commanded force
    # times the scale: orange along it (the raised leg may hide part of one), and none past
    # its tip where its end shows. No arrow at the raised foot.
    orange = hue_mask(frame, FORCE_RGBA)
    forces = loop.last_output.forces
    ends_seen = 0
    for i, leg in enumerate(LEGS):
        contact = feet[leg] - [0.0, 0.0, FOOT_RADIUS_M]
        tip = contact + FORCE_SCALE_M_PER_N * forces[i]
        along = [found(orange, p) for p in pixel_of(contact + np.linspace(0.15, 0.9, 6)[:, None]
                                                     * (tip - contact))]
        if leg == "FR":
            assert not forces[i].any() and not any(along)
            continue
        assert forces[i, 2] > 20.0
        assert np.mean(along) >= 0.5, (leg, along)
        if along[-1]:
            ends_seen += 1
            beyond = pixel_of(contact + 1.25 * (tip - contact))[0]
            assert not found(orange, beyond, radius=1), f"{leg} arrow longer than its force"
    assert ends_seen >= 2

    # MuJoCo's measured forces: blue arrows beside the commanded ones, away from the body.
    blue = hue_mask(frame, MEASURED_RGBA, min_saturation=0.6)
    measured = loop.sim.foot_contact_force_array()
    for leg in ("FL", "RL", "RR"):
        row = LEGS.index(leg)
        out = feet[leg][:2] - com[:2]
        start = feet[leg] - [0.0, 0.0, FOOT_RADIUS_M]
        start[:2] += 0.035 * out / np.linalg.norm(out)
        points = [start + s * FORCE_SCALE_M_PER_N * measured[row] for s in (0.5, 0.7, 0.9)]
        assert any(found(blue, p) for p in pixel_of(points)), leg

    # The raised foot's target: a magenta halo around the foot, and the trace it has followed.
    target = controller.foot_target("FR")
    magenta = hue_mask(frame, TARGET_RGBA, min_value=0.15)
    assert found(magenta, pixel_of(target)[0])
    trace = overlay.traces["FR"]
    assert len(trace) > 20 and trace[0][2] < 0.05 and trace[-1][2] > 0.2
    below = [p for p in trace if 0.1 < p[2] < target[2] - 0.05]  # clear of the halo
    hits = [found(hue_mask(frame, TRACE_RGBA), p) for p in pixel_of(below)]
    assert np.mean(hits) > 0.8

    # The caption, top left: white text that the frame without overlays does not have.
    corner = (slice(0, HEIGHT // 4), slice(0, WIDTH // 2))
    white = frame[corner].min(axis=2) > 230
    assert white.sum() > 100 and (plain[corner].min(axis=2) > 230).sum() < 10


def test_the_legend_is_in_the_frame_s_bottom_left_corner(raising, frames):
    # Each overlay colour's swatch, in its colour, with white text to its right; the frame
    # without overlays has no legend.
    _, overlay, *_ = raising
    frame, plain, *_ = frames
    stamp = LegendStamp(overlay.legend(), frame_height=HEIGHT)
    width, height = stamp.size
    top, left = HEIGHT - stamp.margin_px - height, stamp.margin_px
    assert len(stamp.swatch_centres_px) == 6
    for (column, row), (_, rgba, _) in zip(stamp.swatch_centres_px, overlay.legend(),
                                           strict=True):
        pixel = frame[top + row, left + column].astype(int)
        np.testing.assert_allclose(pixel, np.round(255 * np.array(rgba[:3])), atol=2)
        text = frame[top + row - 3:top + row + 4, left + column + 10:left + width]
        assert (text.min(axis=2) > 200).sum() > 10
    box = (slice(top, top + height), slice(left, left + width))
    assert np.abs(frame[box].astype(int) - plain[box]).mean() > 20


def _legend_frame(entries, *, height: int) -> tuple[np.ndarray, np.ndarray, LegendStamp]:
    grey = np.full((height, height * 4 // 3, 3), 128, np.uint8)
    stamp = LegendStamp(entries, frame_height=height)
    return grey, stamp.stamp(grey.copy()), stamp


def test_the_legend_lists_only_the_overlays_that_are_on():
    assert SceneOverlay(()).legend() == []
    assert SceneOverlay(("target", "com")).legend() == [
        ("red", COM_RGBA, "centre of mass and its ground point"),
        ("magenta", TRACE_RGBA, "raised foot's target and its trace")]
    assert [e[0] for e in SceneOverlay(DEFAULT_OVERLAYS).legend()] == [
        "red", "green", "yellow", "orange", "magenta"]
    every = SceneOverlay(OVERLAY_NAMES, force_scale_m_per_n=0.002)
    assert [e[2] for e in every.legend()][3:5] == ["commanded contact forces (2 mm/N)",
                                                   "measured contact forces (2 mm/N)"]
    assert every.legend_lines() == (
        "red\ngreen\nyellow\norange\nblue\nmagenta",
        ("centre of mass and its ground point\nsupport polygon of the loaded feet\n"
         "support margin: the CoM stays inside\ncommanded contact forces (2 mm/N)\n"
         "measured contact forces (2 mm/N)\nraised foot's target and its trace"))


def test_the_legend_stamp_paints_its_box_and_nothing_else():
    entries = SceneOverlay(OVERLAY_NAMES).legend()
    before, after, stamp = _legend_frame(entries, height=480)
    width, height = stamp.size
    assert stamp.margin_px == 6 and 200 < width < 320 and 80 < height < 130
    top, left = 480 - stamp.margin_px - height, stamp.margin_px
    outside = np.ones(before.shape[:2], bool)
    outside[top:top + height, left:left + width] = False
    assert (after[outside] == before[outside]).all()
    for (column, row), (_, rgba, _) in zip(stamp.swatch_centres_px, entries, strict=True):
        assert tuple(after[top + row, left + column]) == tuple(
            round(255 * c) for c in rgba[:3])
    # The box darkens the grey behind it (black at 150/255), except under the text.
    corner = after[top + 1, left + width - 2].astype(int)
    assert tuple(corner) == (round(128 * 105 / 255),) * 3
    # In proportion in a smaller frame; a frame too small for the box is left alone.
    _, _, small = _legend_frame(entries, height=300)
    assert small.size[1] < 0.75 * height
    tiny = np.zeros((40, 60, 3), np.uint8)
    assert not stamp.stamp(tiny).any()


def test_videos_too_small_to_read_it_or_told_not_to_have_no_legend(raising):
    loop, overlay, _, folder = raising
    for size, legend, has_it in (((320, 240), True, True), ((160, 120), True, False),
                                 ((320, 240), False, False)):
        try:
            recorder = VideoRecorder(loop.sim, folder / "small.mp4", fps=10, size=size,
                                     overlay=overlay, legend=legend)
        except Exception as err:  # noqa: BLE001 - GL backends fail in assorted types
            pytest.skip(f"no offscreen OpenGL on this machine: {' '.join(str(err).split())}")
        recorder.close()
        assert (recorder.legend is not None) == has_it, (size, legend)
    assert 120 < LEGEND_MIN_HEIGHT_PX <= 240


def _rounded(rgba) -> tuple[float, ...]:
    return tuple(round(float(v), 3) for v in rgba)


def test_each_overlay_draws_only_when_switched_on(raising):
    loop, *_ = raising
    colours = {"com": {COM_RGBA}, "polygon": {POLYGON_RGBA, POLYGON_FILL_RGBA, MARGIN_RGBA},
               "forces": {FORCE_RGBA}, "measured": {MEASURED_RGBA},
               "target": {TARGET_RGBA, TRACE_RGBA},
               "gait": {STANCE_RGBA, SWING_RGBA, FOOTHOLD_RGBA, COMMANDED_RGBA,
                        MEASURED_VELOCITY_RGBA}}
    scene = mujoco.MjvScene(loop.sim.model, maxgeom=2000)
    assert SceneOverlay(()).draw(scene, loop) == 0
    # The high five does not walk: the gait overlay is given a motion that does.
    assert SceneOverlay(("gait",)).draw(scene, loop) == 0
    trotting = Trotting()
    for name in OVERLAY_NAMES:
        scene.ngeom = 0
        count = SceneOverlay((name,), gait_of=lambda _: trotting).draw(scene, loop)
        assert count == scene.ngeom > 0, name
        drawn = {_rounded(scene.geoms[i].rgba) for i in range(count)}
        expected = {_rounded(c) for c in colours[name]}
        # A fresh overlay has no trace yet: the target's ball only.
        assert drawn == expected - ({_rounded(TRACE_RGBA)} if name == "target" else set())


def test_a_full_scene_takes_what_fits(raising):
    loop, *_ = raising
    scene = mujoco.MjvScene(loop.sim.model, maxgeom=5)
    assert SceneOverlay(OVERLAY_NAMES).draw(scene, loop) == 5 == scene.ngeom


def test_the_status_panel_names_the_phase_progress_support_and_forces(raising):
    loop, overlay, status, _ = raising
    names, values = overlay.status_lines(loop)
    assert names.splitlines() == ["phase", "progress", "time", "support", "CoM margin",
                                  "normal force"]
    rows = dict(zip(names.splitlines(), values.splitlines(), strict=True))
    assert rows["phase"] == "raising"
    assert rows["progress"] == f"{100 * status['progress']:.0f} %"
    assert rows["time"] == f"{FRAME_S:.2f} s"
    assert rows["support"] == "FL RL RR"
    assert rows["normal force"].startswith("FL ") and " FR 0 " in rows["normal force"]
    assert overlay.caption(loop) == (f"raising  {100 * status['progress']:3.0f} %   "
                                     f"t  {FRAME_S:.2f} s")


class _Handle:
    """What the viewer hook uses of MuJoCo's passive viewer handle, recorded."""

    def __init__(self, model: mujoco.MjModel):
        self.cam = mujoco.MjvCamera()
        self.user_scn = mujoco.MjvScene(model, maxgeom=2000)
        self.texts: list = []
        self.locked = 0
        self.closed = False

    def lock(self):
        handle = self

        class Lock:
            def __enter__(self):
                handle.locked += 1

            def __exit__(self, *exc):
                return False

        return Lock()

    def is_running(self) -> bool:
        return not self.closed

    def set_texts(self, texts):
        self.texts.append(texts)

    def close(self):
        self.closed = True


def test_the_viewer_hook_replaces_the_user_scene_and_shows_the_panel(raising):
    loop, overlay, *_ = raising
    handle = _Handle(loop.sim.model)
    hook = ViewerHook(loop.sim, overlay=overlay, handle=handle)
    assert handle.cam.type == mujoco.mjtCamera.mjCAMERA_TRACKING
    hook.draw_overlay(loop)
    first = handle.user_scn.ngeom
    hook.draw_overlay(loop)
    assert handle.user_scn.ngeom == first > 20  # replaced, not appended
    assert handle.locked == 3  # the camera, then each drawing
    hook.close()  # shows the last panel posted, then stops the text thread
    assert handle.closed
    panel, legend = handle.texts[-1]
    assert panel == (None, mujoco.mjtGridPos.mjGRID_TOPLEFT, *overlay.status_lines(loop))
    assert legend == (None, mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, *overlay.legend_lines())


def test_the_overlay_module_leaves_mujoco_unimported():
    # The command line parses --overlay before it chooses MuJoCo's GL backend.
    code = ("import sys, sim.scene_overlay; "
            "sys.exit(1 if 'mujoco' in sys.modules else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=Path(__file__).parents[1], check=False)
    assert done.returncode == 0, done.stderr
