"""``--plot`` of a run that walked: commanded against measured velocity, the feet's contacts,
the base's height and the control tick, against simulated time."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sim.gait_view import VELOCITY_NAMES, VELOCITY_UNITS, heading_velocities
from sim.plot_axes import control_tick_axis, shade_phases

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: The measured velocity is also drawn as its mean over this window [s]: a trot's base
#: sways at its step frequency, the mean is what tracks the command.
MEAN_WINDOW_S = 0.5


def walked(arrays: dict[str, np.ndarray]) -> bool:
    """Whether the run walked: its arrays hold a commanded velocity on some tick."""
    commanded = arrays.get("commanded_velocity")
    return commanded is not None and bool(np.isfinite(commanded).any())


def moving_mean(t: np.ndarray, values: np.ndarray, window_s: float) -> np.ndarray:
    """The mean of ``values`` (N, ...) over the ``window_s`` [s] centred on each tick (fewer
    ticks at the ends), for ticks of a constant period."""
    if len(t) < 2:
        return np.array(values, dtype=float)
    half = max(0, round(0.5 * window_s / float(np.median(np.diff(t)))))
    cumulative = np.cumsum(np.concatenate([np.zeros((1, *values.shape[1:])), values]), axis=0)
    index = np.arange(len(t))
    low, high = np.maximum(index - half, 0), np.minimum(index + half + 1, len(t))
    counts = (high - low).reshape(-1, *([1] * (values.ndim - 1)))
    return (cumulative[high] - cumulative[low]) / counts


def walking_figure(arrays: dict[str, np.ndarray], *, title: str, caption: str = "") -> Figure:
    """Forward and lateral velocity [m/s] and yaw rate [rad/s]: the command, the simulator's
    truth (each tick, and its :data:`MEAN_WINDOW_S` mean) and the controller's state
    estimate (its mean); which feet MuJoCo finds loaded; the base's height [m] (truth and
    estimate); the control tick [us]; the goal's phases shaded.

    Args:
        arrays: :meth:`sim.run_recorder.TickRecorder.arrays` of a run that walked
            (:func:`walked`): ``commanded_velocity`` (N, 3) among them, NaN where nothing
            walked.
        title: The first title line (the action and its goal).
        caption: The second (plant, rate, state source, estimator).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    from sim.episode_metrics import LOADED_FORCE_N

    t = arrays["t_s"]
    truth = heading_velocities(arrays["q_true"], arrays["v_true"])
    estimate = heading_velocities(arrays["q"], arrays["v"])
    estimated = bool(np.any(arrays["q"] != arrays["q_true"]))
    commanded = arrays["commanded_velocity"]
    fig, axes = plt.subplots(6, 1, sharex=True, figsize=(9, 12), layout="constrained")
    mean = moving_mean(t, truth, MEAN_WINDOW_S)
    estimate_mean = moving_mean(t, estimate, MEAN_WINDOW_S)
    for k, (name, unit) in enumerate(zip(VELOCITY_NAMES, VELOCITY_UNITS, strict=True)):
        ax = axes[k]
        ax.plot(t, truth[:, k], color="tab:blue", lw=0.4, alpha=0.35, label="truth (each tick)")
        ax.plot(t, mean[:, k], color="tab:blue", lw=1.2,
                label=f"truth ({MEAN_WINDOW_S:g} s mean)")
        if estimated:
            ax.plot(t, estimate_mean[:, k], color="tab:purple", lw=0.9, ls="-.",
                    label=f"estimate ({MEAN_WINDOW_S:g} s mean)")
        ax.plot(t, commanded[:, k], color="black", lw=1.2, ls="--", label="commanded")
        ax.set_ylabel(f"{name} [{unit}]")
        ax.legend(loc="upper right", fontsize=7, ncols=2)
    axes[0].set_title("velocity in the heading frame: commanded against measured", fontsize=8,
                      loc="left")
    ax = axes[3]
    legs = [str(leg) for leg in arrays["legs"]]
    loaded = arrays["contact_forces"][:, :, 2] > LOADED_FORCE_N
    for row in range(len(legs)):
        ax.fill_between(t, row - 0.35, row + 0.35, where=loaded[:, row], color="0.25", lw=0,
                        step="mid")
    ax.set_yticks(range(len(legs)), legs)
    ax.set_ylim(len(legs) - 0.5, -0.5)
    ax.set_ylabel(f"loaded feet\n(> {LOADED_FORCE_N:g} N)")
    ax = axes[4]
    ax.plot(t, arrays["q_true"][:, 2], color="tab:blue", label="truth")
    if estimated:
        ax.plot(t, arrays["q"][:, 2], color="tab:purple", lw=0.8, ls="-.", label="estimate")
    ax.set_ylabel("base height [m]")
    ax.legend(loc="upper right", fontsize=7)
    control_tick_axis(axes[5], arrays)
    axes[5].set_xlabel("simulated time [s]")
    shade_phases(plt, fig, axes, t, arrays["phase"], Patch)
    fig.suptitle(f"{title}\n{caption}" if caption else title, fontsize=10)
    return fig
