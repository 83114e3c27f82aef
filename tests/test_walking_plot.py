"""``--plot`` of a run that walked: commanded against measured velocity in the heading frame,
each axis in its unit, the feet's contacts, on synthetic arrays whose velocities are known."""

from __future__ import annotations

import math

import matplotlib
import numpy as np
import pytest

from sim.run_plot import plot_figure
from sim.walking_plot import MEAN_WINDOW_S, moving_mean, walked
from tests.test_run_plot import fake_run

matplotlib.use("Agg")
import matplotlib.pyplot as plt

RATE_HZ, SECONDS = 500, 4.0
#: The base's heading [rad] (the world's y axis): forward is along it.
HEADING = math.pi / 2


def walking_run() -> dict[str, np.ndarray]:
    """4 s at 500 Hz: standing 1 s (no command), then commanded 0.5 m/s forward, 0.1 m/s to
    the left and 0.3 rad/s; the truth moves at the command plus a 4 Hz sway (amplitude
    0.1 m/s forward) from 1 s, the estimate reads 0.02 m/s more forward; FL and RR carry
    load in the first half of each 0.25 s step, FR and RL in the second."""
    n = round(RATE_HZ * SECONDS)
    t = np.arange(n) / RATE_HZ
    walking = t >= 1.0
    commanded = np.full((n, 3), np.nan)
    commanded[walking] = [0.5, 0.1, 0.3]
    forward = np.where(walking, 0.5 + 0.1 * np.sin(2 * math.pi * 4.0 * t), 0.0)
    lateral, yaw_rate = np.where(walking, 0.1, 0.0), np.where(walking, 0.3, 0.0)
    q_true = np.zeros((n, 19))
    q_true[:, 2] = 0.30
    q_true[:, 3:7] = [0.0, 0.0, math.sin(HEADING / 2), math.cos(HEADING / 2)]
    v_true = np.zeros((n, 18))
    # Pinocchio's linear velocity is in the base frame: forward is the base's x axis.
    v_true[:, 0], v_true[:, 1], v_true[:, 5] = forward, lateral, yaw_rate
    q, v = q_true.copy(), v_true.copy()
    q[:, 2] += 0.004
    v[:, 0] += 0.02
    forces = np.zeros((n, 4, 3))
    first_half = (t % 0.25) < 0.125
    forces[:, [0, 3], 2] = np.where(first_half | ~walking, 70.0, 0.0)[:, None]
    forces[:, [1, 2], 2] = np.where(~first_half | ~walking, 70.0, 0.0)[:, None]
    phase = np.where(walking, "walking", "standing")
    return {"t_s": t, "q": q, "v": v, "q_true": q_true, "v_true": v_true,
            "commanded_velocity": commanded, "contact_forces": forces,
            "tick_us": np.full(n, 60.0), "phase": phase, "legs": np.array(["FL", "FR", "RL", "RR"]),
            "raised_leg": np.array("FR"), "foot_position": np.zeros((n, 3)),
            "foot_target": np.full((n, 3), np.nan), "com_margin_m": np.full(n, 0.05)}


@pytest.fixture(scope="module")
def figure():
    fig = plot_figure(walking_run(), title="walk (0.50 m/s for 3 s)", caption="plant menagerie")
    yield fig
    plt.close(fig)


def test_a_run_walked_when_a_tick_has_a_commanded_velocity():
    assert walked(walking_run())
    assert not walked(fake_run())  # a high five's arrays have none
    nothing = walking_run()
    nothing["commanded_velocity"][:] = np.nan
    assert not walked(nothing)


def test_the_moving_mean_is_the_centred_window_s_mean():
    rng = np.random.default_rng(0)
    t = np.arange(200) * 2e-3
    values = rng.normal(size=(200, 3))
    mean = moving_mean(t, values, 0.02)  # 5 ticks either side
    np.testing.assert_allclose(mean[100], values[95:106].mean(axis=0))
    np.testing.assert_allclose(mean[2], values[0:8].mean(axis=0))
    np.testing.assert_allclose(mean[-1], values[-6:].mean(axis=0))


def test_every_axis_names_its_quantity_and_unit(figure):
    labels = [ax.get_ylabel() for ax in figure.axes]
    assert labels == ["forward [m/s]", "lateral [m/s]", "yaw rate [rad/s]",
                      "loaded feet\n(> 1 N)", "base height [m]", "control tick [us]"]
    assert figure.axes[-1].get_xlabel() == "simulated time [s]"
    assert figure._suptitle.get_text() == "walk (0.50 m/s for 3 s)\nplant menagerie"
    legend = [text.get_text() for text in figure.axes[0].get_legend().get_texts()]
    assert legend == ["truth (each tick)", f"truth ({MEAN_WINDOW_S:g} s mean)",
                      f"estimate ({MEAN_WINDOW_S:g} s mean)", "commanded"]


def test_the_measured_velocity_is_read_in_the_heading_frame_against_the_command(figure):
    t = walking_run()["t_s"]
    steady = (t > 1.0 + MEAN_WINDOW_S) & (t < SECONDS - MEAN_WINDOW_S)
    for k, (value, estimate) in enumerate(((0.5, 0.52), (0.1, 0.1), (0.3, 0.3))):
        raw, mean, estimated, commanded = (np.asarray(line.get_ydata())
                                           for line in figure.axes[k].lines)
        # The 0.5 s mean spans two periods of the 4 Hz sway (and one tick): the walking
        # velocity, to 1/251 of the sway's amplitude.
        np.testing.assert_allclose(mean[steady], value, atol=5e-4)
        np.testing.assert_allclose(estimated[steady], estimate, atol=5e-4)
        np.testing.assert_allclose(commanded[t >= 1.0], value)
        assert np.isnan(commanded[t < 1.0]).all()
        assert (raw[steady].max() - raw[steady].min() > 0.19) == (k == 0)  # the sway


def test_the_loaded_feet_show_the_trot_s_diagonal_pairs(figure):
    ax = figure.axes[3]
    assert [tick.get_text() for tick in ax.get_yticklabels()] == ["FL", "FR", "RL", "RR"]
    assert len(ax.collections) == 4  # a band per leg, where MuJoCo found it loaded


def test_the_base_height_and_the_phases_are_shown(figure):
    truth, estimate = figure.axes[4].lines[:2]
    np.testing.assert_allclose(truth.get_ydata(), 0.30)
    np.testing.assert_allclose(estimate.get_ydata(), 0.304)
    legend = [text.get_text() for text in figure.legends[0].get_texts()]
    assert legend == ["standing", "walking"]
