"""A walk seen: the gait overlay found in the pixels of a frame rendered mid-trot, the viewer's
panel and the video's legend naming it, and the per-tick log and plot of the same walk."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from actions.go2.go2_interfaces import WalkGoal
from sim.control_loop import ControlLoop
from sim.gait_overlay import (
    ARROW_HEIGHT_M,
    COMMANDED_RGBA,
    MEASURED_VELOCITY_RGBA,
    STANCE_DISC_M,
    STANCE_RGBA,
    SWING_RGBA,
)
from sim.gait_view import walking_motion
from sim.run_plot import plot_figure
from sim.run_recorder import TickRecorder
from sim.scene_geoms import FLOOR_Z
from sim.scene_overlay import SceneOverlay
from sim.video_recorder import LegendStamp, VideoRecorder
from tests.test_scene_overlay import found, hue_mask, project
from wbc.model.description import LEGS

pytestmark = pytest.mark.slow  # a loop built, a walk started and a frame rendered: ~10 s

WIDTH, HEIGHT = 480, 360
COMMAND = (0.5, 0.0, 0.5)


@pytest.fixture(scope="module")
def trotting():
    """A loop 1.2 s or more into a walk's walking phase, two feet well up in swing; its
    per-tick log; the walking motion."""
    loop = ControlLoop.simulated()
    loop.spin_for(0.3)
    recorder = TickRecorder(lambda: "", loop=loop)
    loop.hooks.append(recorder)
    loop.spin_for(0.05)  # standing, recorded
    forward, lateral, yaw_rate = COMMAND
    loop.client("walk").send_goal_async(WalkGoal(forward_mps=forward, lateral_mps=lateral,
                                                 yaw_rate_radps=yaw_rate, duration_s=10.0))
    walked_from = None
    while loop.robot.time_s < 6.0:
        loop.spin_once()
        walking = walking_motion(loop)
        if walking is None or str(walking.phase) != "walking":
            continue
        walked_from = walked_from or loop.robot.time_s
        feet = loop.controller.foot_positions()
        up = [leg for leg in walking.swing_legs if feet[LEGS.index(leg), 2] > 0.05]
        if loop.robot.time_s > walked_from + 1.2 and len(up) == 2 and set(
                walking.footholds) >= set(up):
            break
    else:
        pytest.fail("no frame with two feet 5 cm up in the walking phase within 6 s")
    return loop, recorder, walking


@pytest.fixture(scope="module")
def frames(trotting, tmp_path_factory: pytest.TempPathFactory):
    loop, _, _ = trotting
    overlay = SceneOverlay(("gait",))
    path = tmp_path_factory.mktemp("walk") / "frame.mp4"
    try:
        recorder = VideoRecorder(loop.sim, path, fps=30, size=(WIDTH, HEIGHT),
                                 overlay=overlay)
    except Exception as err:  # noqa: BLE001 - GL backends fail in assorted types
        pytest.skip(f"no offscreen OpenGL on this machine: {' '.join(str(err).split())}")
    try:
        legend_before = recorder.legend
        frame = recorder.render(loop)
        scene = recorder.renderer.scene

        def pixel_of(points):
            return project(scene, np.asarray(points, float), WIDTH, HEIGHT)

        legend = recorder.legend
        recorder.overlay = None
        plain = recorder.render(loop)
    finally:
        recorder.close()
    return frame, plain, pixel_of, overlay, (legend_before, legend)


def test_the_stance_and_swing_feet_and_the_footholds_are_drawn(trotting, frames):
    loop, _, walking = trotting
    frame, plain, pixel_of, *_ = frames
    feet = loop.controller.foot_positions()
    swing = walking.swing_legs
    assert len(swing) == 2 and set(swing) in ({"FL", "RR"}, {"FR", "RL"})  # a trot
    cyan, violet = hue_mask(frame, STANCE_RGBA), hue_mask(frame, SWING_RGBA)
    ring = [(math.cos(a), math.sin(a)) for a in np.linspace(0, 2 * math.pi, 12, endpoint=False)]
    for i, leg in enumerate(LEGS):
        if leg in swing:
            assert found(violet, pixel_of(feet[i])[0], radius=3), leg
            hold = walking.footholds[leg]
            assert found(violet, pixel_of([hold[0], hold[1], FLOOR_Z])[0], radius=3), leg
            continue
        # The disc's rim, outside the foot (the leg hides part of it).
        rim = [[feet[i, 0] + 0.8 * STANCE_DISC_M * c, feet[i, 1] + 0.8 * STANCE_DISC_M * s,
                FLOOR_Z] for c, s in ring]
        assert sum(found(cyan, p) for p in pixel_of(rim)) >= 3, leg
    for colour in (STANCE_RGBA, SWING_RGBA):
        assert not hue_mask(plain, colour).any()


def test_the_commanded_and_measured_velocities_are_arrows_over_the_base(trotting, frames):
    loop, _, _ = trotting
    frame, plain, pixel_of, overlay, _ = frames
    view = overlay.gait_view(loop)
    np.testing.assert_allclose(view.commanded, COMMAND, atol=1e-9)  # reached by now
    assert 0.2 < view.measured[0] < 0.8
    start = view.base_position + [0.0, 0.0, ARROW_HEIGHT_M]
    for which, rgba, lift in (("commanded", COMMANDED_RGBA, 0.0),
                              ("measured", MEASURED_VELOCITY_RGBA, 0.02)):
        tip = start + [0.0, 0.0, lift] + view.world_velocity(which)
        along = pixel_of(start + [0.0, 0.0, lift] + np.linspace(0.2, 0.8, 7)[:, None]
                         * (tip - start - [0.0, 0.0, lift]))
        mask = hue_mask(frame, rgba, min_saturation=0.4)
        assert np.mean([found(mask, p) for p in along]) >= 0.7, which
        assert not hue_mask(plain, rgba, min_saturation=0.4).any()


def test_the_panel_and_the_legend_name_the_gait(trotting, frames):
    loop, _, walking = trotting
    *_, overlay, (before, after) = frames
    names, values = overlay.status_lines(loop)
    rows = dict(zip(names.splitlines(), values.splitlines(), strict=True))
    assert rows["swing"] == " ".join(walking.swing_legs)
    assert rows["commanded"] == "+0.50 m/s  +0.00 m/s  +0.50 rad/s"
    assert rows["measured"].count("m/s") == 2 and rows["measured"].endswith("rad/s")
    # No legend until a gait was drawn; then its four colours.
    assert before is None and isinstance(after, LegendStamp)
    assert [e[0] for e in after.entries] == ["cyan", "violet", "pink", "lime"]


def test_the_log_holds_the_command_and_the_plot_shows_its_tracking(trotting):
    _, recorder, _ = trotting
    arrays = recorder.arrays()
    commanded = arrays["commanded_velocity"]
    assert commanded.shape == (len(arrays["t_s"]), 3)
    assert np.isnan(commanded[:50]).all()  # standing: nothing walked
    np.testing.assert_allclose(commanded[-1], COMMAND)
    ramp = commanded[np.isfinite(commanded[:, 0]), 0]
    assert ramp[0] < 0.1 and np.all(np.diff(ramp) >= -1e-12)  # ramped up to the command
    fig = plot_figure(arrays, title="walk", caption="")
    assert [ax.get_ylabel() for ax in fig.axes][:3] == ["forward [m/s]", "lateral [m/s]",
                                                         "yaw rate [rad/s]"]
    plt.close(fig)


def test_go2_wbc_walk_writes_its_plot_and_log(tmp_path):
    from sim.cli import main

    paths = {name: tmp_path / f"walk.{name}" for name in ("png", "npz")}
    code, out = run_cli(["walk", "--forward", "0.4", "--yaw-rate", "0.3", "--duration", "1",
                         "--plot", str(paths["png"]), "--log", str(paths["npz"])], main)
    assert code == 0, out
    assert "walk: sending goal (forward 0.4 m/s, lateral 0 m/s, yaw rate 0.3 rad/s, for 1 s)" in out
    assert "result: SUCCEEDED" in out
    log = np.load(paths["npz"])
    commanded = log["commanded_velocity"]
    walking = np.isfinite(commanded[:, 0])
    assert walking.sum() > 900  # the walk's ticks, from its start to its stop
    assert np.allclose(commanded[walking].max(axis=0), [0.4, 0.0, 0.3])
    assert paths["png"].read_bytes().startswith(b"\x89PNG")


def run_cli(argv: list[str], main) -> tuple[int, str]:
    """``main(argv)`` in this process: the exit code and what it printed."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue()
