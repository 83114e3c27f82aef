"""Minimum-jerk interpolation: zero velocity and acceleration at both ends."""

from __future__ import annotations

import numba
import numpy as np


# Explicit signatures: numba compiles (or reads from its cache) these at import, not at
# their first call, which would cost milliseconds inside the control tick that starts a
# motion.
@numba.njit("UniTuple(float64, 3)(float64)", cache=True)
def min_jerk(tau: float) -> tuple[float, float, float]:
    """Phase ``s``, ``ds/dtau`` and ``d2s/dtau2`` of the minimum-jerk profile at ``tau``.

    ``s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5``, clamped to ``[0, 1]`` outside ``[0, 1]``.
    """
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0
    t2 = tau * tau
    # Rounding can push the polynomial a hair past 1 just before the end: clamp it.
    s = min(1.0, t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2))
    ds = 30.0 * t2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
    return s, ds, dds


def min_jerk_segment(start: np.ndarray, end: np.ndarray, elapsed_s: float,
                     duration_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration on a minimum-jerk line from ``start`` to ``end``.

    Args:
        start, end: End points (any shape, same units).
        elapsed_s: Time since the segment began [s].
        duration_s: Segment duration [s] (> 0).
    """
    s, ds, dds = min_jerk(elapsed_s / duration_s)
    delta = np.asarray(end) - np.asarray(start)
    return start + s * delta, (ds / duration_s) * delta, (dds / duration_s**2) * delta


@numba.njit("void(float64[:, :], float64[:], float64[:], float64, float64, float64, float64)",
            cache=True)
def min_jerk_reference(out: np.ndarray, start: np.ndarray, end: np.ndarray, elapsed_s: float,
                       duration_s: float, lateral_delay: float,
                       lateral_share: float) -> None:  # pragma: no cover - compiled
    """Position, velocity and acceleration on a minimum-jerk move, into ``out``'s rows (3, n).

    The vertical axes (from the third on) move over the whole ``duration_s`` [s]; the first
    two (horizontal) start ``lateral_delay`` and last ``lateral_share`` of it (fractions):
    ``0, 1`` moves every axis together; ``0.25, 0.75`` lifts a foot off vertically first;
    ``0, 0.75`` sets it down vertically last. One compiled call, no allocation: for the
    references a motion sets every control tick.
    """
    tau = elapsed_s / duration_s
    s, ds, dds = min_jerk(tau)
    rate, curvature = 1.0 / duration_s, 1.0 / (duration_s * duration_s)
    lateral = 1.0 / (lateral_share * duration_s)
    sl, dsl, ddsl = min_jerk((tau - lateral_delay) / lateral_share)
    for k in range(out.shape[1]):
        delta = end[k] - start[k]
        if k < 2:
            out[0, k] = start[k] + sl * delta
            out[1, k] = dsl * lateral * delta
            out[2, k] = ddsl * lateral * lateral * delta
        else:
            out[0, k] = start[k] + s * delta
            out[1, k] = ds * rate * delta
            out[2, k] = dds * curvature * delta
