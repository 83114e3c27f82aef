"""``--plot``: units on every axis, the support switches marked, a band for ``complete``, and a
title that names the plant, the rate, the estimator and the state source (synthetic arrays)."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest

from sim.cli.output import run_caption
from sim.episode import Episode
from sim.run_plot import plot_figure, support_switches, write_plot

matplotlib.use("Agg")
import matplotlib.pyplot as plt

LEGS = ("FL", "FR", "RL", "RR")


def fake_run(*, estimated: bool = True) -> dict[str, np.ndarray]:
    """3 s at 1 kHz: FR unloads at 1 s (flickering 3 ticks at the threshold), is loaded again
    at 2 s; the goal reports ``complete`` on the last tick."""
    n = 3000
    t = 0.3 + np.arange(n) * 1e-3
    forces = np.zeros((n, 4, 3))
    forces[:, :, 2] = 40.0
    fr = forces[:, 1, 2]
    fr[1000:2000] = 0.0
    fr[1001] = fr[1003] = 2.0  # the flicker: loaded for a tick, twice
    q_true = np.zeros((n, 19))
    q_true[:, 2] = 0.3
    q = q_true.copy()
    v = np.zeros((n, 18))
    if estimated:
        q[:, 2] += 0.8e-3
        v[:, 0] = 0.5e-3
    phase = np.array(["shifting"] * 1000 + ["raising"] * 1000 + ["shifting_back"] * 999
                     + ["complete"])
    margin = np.where(fr > 1.0, 0.1, 0.06)
    return {"t_s": t, "q": q, "v": v, "q_true": q_true, "v_true": np.zeros((n, 18)),
            "foot_position": np.zeros((n, 3)), "foot_target": np.full((n, 3), np.nan),
            "contact_forces": forces, "com_margin_m": margin, "tick_us": np.full(n, 40.0),
            "phase": phase, "legs": np.array(LEGS), "raised_leg": np.array("FR")}


@pytest.fixture(scope="module")
def figure():
    fig = plot_figure(fake_run(), title="high_five (target_height 0.40 m, hold 2 s)",
                      caption="plant menagerie, control 1000 Hz; state estimated by inekf")
    yield fig
    plt.close(fig)


def test_switches_are_marked_once_each_way_despite_a_flicker() -> None:
    run = fake_run()
    switches = support_switches(run["t_s"], run["contact_forces"])
    assert [(round(t, 3), before, after) for t, before, after in switches] == [
        (1.3, 4, 3), (2.3, 3, 4)]


def test_every_quantity_has_its_own_axis_and_unit(figure) -> None:
    labels = [ax.get_ylabel() for ax in figure.axes]
    assert labels == ["FR foot height [m]", "CoM margin [mm]", "FR normal force [N]",
                      "base height error\n[mm]", "base velocity error\n[mm/s]",
                      "control tick [us]"]
    height, velocity = figure.axes[3].lines[0], figure.axes[4].lines[0]
    assert np.allclose(height.get_ydata(), 0.8)  # mm
    assert np.allclose(velocity.get_ydata(), 0.5)  # mm/s


def test_the_margin_s_steps_are_annotated(figure) -> None:
    texts = [text.get_text() for text in figure.axes[1].texts]
    assert texts == ["FR unloaded: 4 feet -> triangle", "FR loaded: triangle -> 4 feet"]
    xs = sorted(line.get_xdata()[0] for line in figure.axes[1].lines[2:])
    assert np.allclose(xs, [1.3, 2.3])


def test_complete_has_a_band_past_the_last_tick(figure) -> None:
    ax = figure.axes[0]
    start, end = (ax.patches[-1].get_x(),
                  ax.patches[-1].get_x() + ax.patches[-1].get_width())
    assert start == pytest.approx(3.299) and end == pytest.approx(3.299 + 0.03 * 2.999)
    assert ax.get_xlim()[1] > end
    assert "complete" in [text.get_text() for text in ax.texts]
    legend = [text.get_text() for text in figure.legends[0].get_texts()]
    assert legend == ["shifting", "raising", "shifting_back", "complete"]


def test_the_title_names_the_run(figure) -> None:
    assert figure._suptitle.get_text() == ("high_five (target_height 0.40 m, hold 2 s)\n"
                                           "plant menagerie, control 1000 Hz; state estimated "
                                           "by inekf")


def test_the_caption_names_plant_rate_estimator_and_state_source() -> None:
    assert run_caption(Episode()) == ("plant menagerie, control 1000 Hz; state estimated by "
                                      "inekf from sensors go2, seed 0")
    assert run_caption(Episode(plant="identified", control_period_s=2e-3, state="truth")) == (
        "plant identified, control 500 Hz; state: the simulator's truth (no estimator)")
    assert run_caption(Episode(estimator="kf", sensor_seed=3)).endswith(
        "state estimated by kf from sensors go2, seed 3")


@pytest.mark.slow  # writes a 3000-tick PNG: seconds
def test_truth_says_there_is_no_estimate_and_the_png_is_written(tmp_path: Path) -> None:
    path = tmp_path / "truth.png"
    write_plot(path, fake_run(estimated=False), title="t", caption="c")
    assert path.read_bytes().startswith(b"\x89PNG")
    fig = plot_figure(fake_run(estimated=False), title="t")
    assert [text.get_text() for text in fig.axes[3].texts] == [
        "the controller read the simulator's truth: no estimate"]
    plt.close(fig)
