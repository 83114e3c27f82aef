"""``--plot``: a run's per-tick arrays in one figure: each quantity on its own axis, in its unit
(a run that walked: :func:`sim.walking_plot.walking_figure`)."""

from __future__ import annotations

from itertools import pairwise
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sim.plot_axes import COMPLETE as COMPLETE  # its home; kept importable from here
from sim.plot_axes import control_tick_axis, shade_phases

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def support_switches(t: np.ndarray, forces: np.ndarray, *,
                     min_ticks: int = 20) -> list[tuple[float, int, int]]:
    """``(t [s], loaded feet before, after)`` at each tick the number of loaded feet (normal
    force above ``sim.episode_metrics.LOADED_FORCE_N``, as the CoM margin counts them)
    changes between four and three: where the margin's polygon switches between the four
    feet and a triangle."""
    # Here, not at import: sim.episode_metrics imports MuJoCo, which a --video run must not
    # import before it has chosen its rendering backend.
    from sim.episode_metrics import LOADED_FORCE_N

    loaded = (forces[:, :, 2] > LOADED_FORCE_N).sum(axis=1)
    # A foot near the threshold flickers for a few ticks: a count held for less than
    # min_ticks is the one before it, so each switch is marked once.
    starts = [0, *(np.flatnonzero(np.diff(loaded)) + 1).tolist(), len(loaded)]
    held = int(loaded[0]) if len(loaded) else 0
    pending = None  # where the count first left ``held``: the switch's time once it holds
    switches = []
    for start, end in pairwise(starts[1:]):
        count, long = int(loaded[start]), end - start >= min_ticks
        if count == held:
            pending = None if long else pending
            continue
        pending = start if pending is None else pending
        if long:
            if {held, count} == {3, 4}:
                switches.append((float(t[pending]), held, count))
            held, pending = count, None
    return switches


def _annotate_switches(ax: Axes, t: np.ndarray, margin_mm: np.ndarray,
                       switches: list[tuple[float, int, int]], leg: str) -> None:
    """Mark where the margin steps because its polygon changed, not because the CoM moved."""
    for time_s, _, after in switches:
        i = int(np.searchsorted(t, time_s))
        y = float(np.nanmin(margin_mm[max(0, i - 5):i + 5]))
        text = (f"{leg} unloaded: 4 feet -> triangle" if after == 3
                else f"{leg} loaded: triangle -> 4 feet")
        ax.axvline(time_s, color="0.3", lw=0.8, ls="--")
        ax.annotate(text, xy=(time_s, y), xytext=(6 if after == 3 else -6, -14),
                    textcoords="offset points", fontsize=7.5,
                    ha="left" if after == 3 else "right", va="top")


def write_plot(path: Path, arrays: dict[str, np.ndarray], *, title: str,
               caption: str = "") -> None:
    """Write :func:`plot_figure`'s figure to ``path`` (PNG)."""
    import matplotlib.pyplot as plt

    fig = plot_figure(arrays, title=title, caption=caption)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_figure(arrays: dict[str, np.ndarray], *, title: str, caption: str = "") -> Figure:
    """The raised foot's height against its target [m], the CoM margin [mm] with the steps
    where the support polygon switches, the raised foot's normal force [N], the estimate's
    base height error [mm] and velocity error [mm/s] against the truth, and each control
    tick's time [us], against simulated time, the goal's phases shaded. A run that walked
    (:func:`sim.walking_plot.walked`) gets :func:`sim.walking_plot.walking_figure`: commanded
    against measured velocity.

    Args:
        arrays: :meth:`sim.run_recorder.TickRecorder.arrays` (or a recording's).
        title: The first title line (the action and its goal).
        caption: The second (:func:`sim.cli.output.run_caption`: plant, rate, state
            source, estimator).
    """
    from sim.walking_plot import walked, walking_figure

    if walked(arrays):
        return walking_figure(arrays, title=title, caption=caption)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Patch

    t = arrays["t_s"]
    leg = str(arrays["raised_leg"])
    column = list(arrays["legs"]).index(leg)
    fig, axes = plt.subplots(6, 1, sharex=True, figsize=(9, 12), layout="constrained")
    ax = axes[0]
    ax.plot(t, arrays["foot_position"][:, 2], label=f"{leg} foot (MuJoCo)")
    ax.plot(t, arrays["foot_target"][:, 2], "--", label="target")
    ax.set_ylabel(f"{leg} foot height [m]")
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[1]
    margin_mm = arrays["com_margin_m"] * 1e3
    ax.plot(t, margin_mm)
    ax.axhline(0.0, color="tab:red", lw=0.8, ls=":", label="support edge")
    _annotate_switches(ax, t, margin_mm, support_switches(t, arrays["contact_forces"]), leg)
    ax.set_ylabel("CoM margin [mm]")
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[2]
    ax.plot(t, arrays["contact_forces"][:, column, 2])
    ax.set_ylabel(f"{leg} normal force [N]")
    error_height_mm = (arrays["q"][:, 2] - arrays["q_true"][:, 2]) * 1e3
    error_velocity_mm_s = np.linalg.norm(arrays["v"][:, :3] - arrays["v_true"][:, :3],
                                         axis=1) * 1e3
    estimated = bool(np.any(error_height_mm) or np.any(error_velocity_mm_s))
    for ax, error, label in ((axes[3], error_height_mm, "base height error\n[mm]"),
                             (axes[4], error_velocity_mm_s, "base velocity error\n[mm/s]")):
        ax.plot(t, error, color="tab:purple")
        ax.axhline(0.0, color="0.5", lw=0.6)
        ax.set_ylabel(label)
        if not estimated:  # --state truth: nothing to compare
            ax.text(0.5, 0.5, "the controller read the simulator's truth: no estimate",
                    transform=ax.transAxes, ha="center", va="center", fontsize=8)
    axes[3].set_title("the state estimate against the simulator's truth (|v| for the "
                      "velocity)", fontsize=8, loc="left")
    control_tick_axis(axes[5], arrays)
    axes[5].set_xlabel("simulated time [s]")
    shade_phases(plt, fig, axes, t, arrays["phase"], Patch)
    fig.suptitle(f"{title}\n{caption}" if caption else title, fontsize=10)
    return fig
