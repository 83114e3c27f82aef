"""Axes every ``--plot`` figure shares: the control tick's time, the goal's phases shaded."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: The phase a goal ends in: the run stops on its tick, so its band is drawn past the end.
COMPLETE = "complete"


def control_tick_axis(ax: Axes, arrays: dict[str, np.ndarray]) -> None:
    """Each control tick's time [us] (log scale) and the control period."""
    t = arrays["t_s"]
    ax.plot(t, arrays["tick_us"], lw=0.5)
    if "control_period_s" in arrays:  # a recording's rows are snapshots, not ticks
        period_us = float(arrays["control_period_s"]) * 1e6
    else:
        period_us = float(np.median(np.diff(t))) * 1e6 if len(t) > 1 else 1e3
    ax.axhline(period_us, color="tab:red", lw=0.8, ls=":",
               label=f"control period ({1e6 / period_us:.0f} Hz)")
    ax.set_yscale("log")  # the first tick builds the solver workspace: 100x the others
    ax.set_ylabel("control tick [us]")
    ax.legend(loc="upper right", fontsize=8)


def shade_phases(plt: Any, fig: Any, axes: Any, t: np.ndarray, phases: np.ndarray,
                  patch: Any) -> None:
    """A band per phase on every axis and a legend of them. The goal ends on the tick it
    reports ``complete``, so that phase gets a band past the last tick (the axis widened by
    3 %), labelled, rather than a band of no width."""
    starts = [0] + [i for i in range(1, len(phases)) if phases[i] != phases[i - 1]]
    colours: dict[str, Any] = {}
    palette = plt.get_cmap("Pastel1").colors + plt.get_cmap("Pastel2").colors
    span = float(t[-1] - t[0]) if len(t) > 1 else 1.0
    for k, start in enumerate(starts):
        last = k + 1 == len(starts)
        end = float(t[starts[k + 1]]) if not last else float(t[-1])
        name = str(phases[start]) or "(waiting)"
        if last and name == COMPLETE:
            end = float(t[start]) + 0.03 * span
            axes[0].text(t[start] + 0.015 * span, 0.5, "complete", rotation=90,
                         transform=axes[0].get_xaxis_transform(), ha="center", va="center",
                         fontsize=7.5)
        colour = colours.setdefault(name, palette[len(colours) % len(palette)])
        for ax in axes:
            ax.axvspan(t[start], end, color=colour, alpha=0.6, lw=0, zorder=0)
    axes[-1].set_xlim(float(t[0]) - 0.01 * span, float(t[-1]) + 0.04 * span)
    fig.legend(handles=[patch(color=c, label=n) for n, c in colours.items()],
               loc="outside lower center", ncols=min(len(colours), 6), fontsize=8)
