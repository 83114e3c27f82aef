"""The joint trajectory between a FollowJointTrajectory goal's points: splines through them."""

from __future__ import annotations

import numpy as np

# scipy's splines are well tested, including the end conditions and Hermite data we need;
# a hand-written banded solve would buy nothing.
from scipy.interpolate import BPoly, make_interp_spline

from actions.go2.trajectory_plan import TrajectoryPlan


class JointSpline:
    """Positions, velocities and accelerations of the goal's joints at trajectory time t."""

    def __init__(self, plan: TrajectoryPlan, start: np.ndarray):
        times = np.concatenate([[0.0], plan.times_s])
        zeros = np.zeros_like(start)
        if plan.velocities is None:
            rest = [(1, zeros), (2, zeros)]
            spline = make_interp_spline(times, np.vstack([start, plan.positions]), k=5,
                                        bc_type=(rest, rest))
        else:
            fields = [plan.positions, plan.velocities]
            if plan.accelerations is not None:
                fields.append(plan.accelerations)
            at_start = np.array([start, *[zeros] * (len(fields) - 1)])
            at_points = [np.array([f[i] for f in fields]) for i in range(len(times) - 1)]
            spline = BPoly.from_derivatives(times, [at_start, *at_points])
        self._curves = (spline, spline.derivative(1), spline.derivative(2))
        self._start, self._end, self._duration = start, plan.positions[-1], plan.duration_s

    def sample(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities, accelerations at ``t`` [s]; at rest before 0 and after the end."""
        if t <= 0.0 or t >= self._duration:
            held = self._start if t <= 0.0 else self._end
            return held.copy(), np.zeros_like(held), np.zeros_like(held)
        return tuple(np.asarray(curve(t), dtype=float) for curve in self._curves)
