"""A swing foot's path: up, across and down, smooth, at rest at lift-off and touch-down."""

from __future__ import annotations

import numba
import numpy as np

from wbc.core.min_jerk import min_jerk


@numba.njit("void(f8[:, :], f8, f8, f8, f8, f8, f8, f8, f8, f8)", cache=True)
def swing_path(out: np.ndarray, sx: float, sy: float, sz: float, ex: float, ey: float,
               ez: float, height_m: float, progress: float,
               duration_s: float) -> None:  # pragma: no cover - compiled
    """:func:`swing_reference` from the end points' coordinates [m] into ``out`` (3, 3): its
    one implementation, which the walking tick's compiled kernel calls too."""
    tau = min(max(progress, 0.0), 1.0)
    s, ds, dds = min_jerk(tau)
    rate, curvature = 1.0 / duration_s, 1.0 / (duration_s * duration_s)
    dx, dy = ex - sx, ey - sy
    out[0, 0], out[1, 0], out[2, 0] = sx + s * dx, ds * rate * dx, dds * curvature * dx
    out[0, 1], out[1, 1], out[2, 1] = sy + s * dy, ds * rate * dy, dds * curvature * dy
    apex = (sz if sz > ez else ez) + height_m
    # Each half lasts duration_s / 2: its time derivatives scale by 2 and 4.
    if tau < 0.5:
        s, ds, dds = min_jerk(2.0 * tau)
        low = sz
    else:
        s, ds, dds = min_jerk(2.0 - 2.0 * tau)  # from the end backwards: the descent
        ds = -ds
        low = ez
    delta = apex - low
    out[0, 2] = low + s * delta
    out[1, 2] = 2.0 * ds * rate * delta
    out[2, 2] = 4.0 * dds * curvature * delta


def swing_reference(out: np.ndarray, start: np.ndarray, end: np.ndarray, *, height_m: float,
                    progress: float, duration_s: float) -> np.ndarray:
    """Position [m], velocity [m/s] and acceleration [m/s^2] of a swing foot, into ``out``'s
    rows (3, 3); returns ``out``.

    The horizontal motion is one minimum-jerk move from ``start`` to ``end`` over the whole
    swing; the vertical one rises by ``height_m`` above the higher end point in the first
    half and falls to ``end`` in the second, each half a minimum-jerk move. Position,
    velocity and acceleration are continuous, and zero velocity and acceleration at both
    ends: the foot leaves and lands without a jolt. ``end`` may change during the swing (a
    foothold re-planned): the path bends towards it smoothly.

    Args:
        out: (3, 3) float64 array: rows position, velocity, acceleration; columns x, y, z.
        start: Lift-off position (3,) [m].
        end: Touch-down position (3,) [m].
        height_m: Apex above the higher of the two end points [m].
        progress: Fraction of the swing done, clamped to ``[0, 1]``.
        duration_s: The swing's duration [s] (> 0).
    """
    sx, sy, sz = np.asarray(start, dtype=float).tolist()
    ex, ey, ez = np.asarray(end, dtype=float).tolist()
    swing_path(out, sx, sy, sz, ex, ey, ez, float(height_m), float(progress),
               float(duration_s))
    return out
