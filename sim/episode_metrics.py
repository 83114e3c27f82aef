"""Quality metrics of a closed-loop episode, measured in MuJoCo tick by tick."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numba
import numpy as np

from sim.simulator import Go2Simulator
from wbc.control_output import ControlOutput
from wbc.description import LEGS
from wbc.support_polygon import shrunk_signed_distance

#: A foot carrying less than this [N] counts as unloaded.
LOADED_FORCE_N = 1.0

_F64 = numba.float64


@numba.njit(numba.int64(numba.boolean[::1], _F64[:, ::1], _F64[:, ::1], _F64[:, ::1], _F64,
                        _F64[:, ::1], _F64[:, ::1], _F64[:, ::1], _F64[::1]), cache=True)
def _feet(stance, sliding, positions, forces, dt, slid, ground, loaded, stats):
    """One tick of the feet's measures; returns how many feet are loaded.

    A stance foot integrates its sliding (``slid += sliding dt``) and its travel from
    ``ground``; any other foot starts afresh. ``stats`` holds the running sliding maximum,
    travel maximum and minimum stance normal force. ``loaded`` gets the positions of the
    feet carrying more than :data:`LOADED_FORCE_N`, first rows first.
    """
    count = 0
    for i in range(stance.shape[0]):
        if stance[i]:
            slid[i, 0] += sliding[i, 0] * dt
            slid[i, 1] += sliding[i, 1] * dt
            stats[0] = max(stats[0], math.sqrt(slid[i, 0] ** 2 + slid[i, 1] ** 2))
            dx = positions[i, 0] - ground[i, 0]
            dy = positions[i, 1] - ground[i, 1]
            stats[1] = max(stats[1], math.sqrt(dx * dx + dy * dy))
            stats[2] = min(stats[2], forces[i, 2])
        else:  # a foot that leaves the ground starts afresh when it lands
            slid[i, 0] = 0.0
            slid[i, 1] = 0.0
            for k in range(3):
                ground[i, k] = positions[i, k]
        if forces[i, 2] > LOADED_FORCE_N:
            for k in range(3):
                loaded[count, k] = positions[i, k]
            count += 1
    return count


@numba.njit(numba.void(_F64[:], _F64[::1], _F64[:], numba.boolean, _F64[::1]), cache=True)
def _torques(tau, previous, limit, has_previous, stats):
    """Largest ``|tau| / limit`` into ``stats[3]``, largest jump from ``previous`` into
    ``stats[4]``; ``previous`` becomes ``tau``."""
    for i in range(tau.shape[0]):
        stats[3] = max(stats[3], abs(tau[i]) / limit[i])
        if has_previous:
            stats[4] = max(stats[4], abs(tau[i] - previous[i]))
        previous[i] = tau[i]


@dataclass
class EpisodeSummary:
    """What an episode achieved. Lengths [mm], forces [N], angles [deg], times [us]."""

    duration_s: float
    ticks: int
    raised_foot_rms_mm: float
    raised_foot_max_mm: float
    holding_rms_mm: float
    holding_max_mm: float
    #: Largest sliding of a stance foot's contact point on the floor.
    stance_sliding_max_mm: float
    #: Largest horizontal travel of a stance foot's centre (rolling included).
    stance_travel_max_mm: float
    min_stance_normal_force_n: float
    min_com_margin_mm: float
    max_base_tilt_deg: float
    max_torque_fraction: float
    max_torque_jump_nm: float
    qp_failures: int
    tick_median_us: float
    tick_p99_us: float
    tick_max_us: float
    real_time_factor: float
    fell: bool

    def as_dict(self) -> dict[str, float | int | bool]:
        """Plain values, JSON-ready."""
        return {k: (round(v, 4) if isinstance(v, float) else v) for k, v in asdict(self).items()}


class EpisodeMetrics:
    """Accumulates per-tick measurements; :meth:`summary` condenses them.

    Call :meth:`record` after each ``sim.step``. The raised foot's tracking error is
    measured only while ``tracking`` is true (the foot is in the air following a target);
    ``holding`` marks the hold phase. Stance feet are the feet the controller has in
    stance at full load; their sliding is integrated from the contact point's velocity.
    """

    def __init__(self, sim: Go2Simulator, effort_limit: np.ndarray):
        self.sim = sim
        self.effort_limit = np.asarray(effort_limit, dtype=float)
        self.start_s = sim.time_s
        self._last_s = sim.time_s
        n = len(LEGS)
        self._slid = np.zeros((n, 2))  # integrated sliding of each stance foot [m]
        self._ground = sim.foot_position_array()  # where each stance foot stood [m]
        self._stance = np.zeros(n, dtype=bool)
        self._sliding = np.zeros((n, 2))
        self._forces = np.zeros((n, 3))
        self._positions = np.zeros((n, 3))
        self._loaded = np.zeros((n, 3))
        self._tau_prev = np.zeros(len(self.effort_limit))
        #: Running sliding max, travel max, min force, torque fraction, torque jump.
        self._stats = np.array([0.0, 0.0, math.inf, 0.0, 0.0])
        self.tracking_errors: list[float] = []
        self.holding_errors: list[float] = []
        self.sliding_max = 0.0
        self.travel_max = 0.0
        self.min_force = math.inf
        self.min_margin = math.inf
        self.max_tilt = 0.0
        self.max_torque_fraction = 0.0
        self.max_jump = 0.0
        self.failures = 0
        self.tick_times: list[float] = []
        self.fell = False
        self.ticks = 0

    def record(self, out: ControlOutput, *, stance_legs: list[str],
               foot_error_m: float | None = None, holding: bool = False,
               tick_time_s: float | None = None) -> None:
        """Measure one tick.

        Args:
            out: The controller's output this tick.
            stance_legs: Legs that must stay put (fully loaded stance feet).
            foot_error_m: Raised-foot position error [m], when a foot tracks a target.
            holding: The raised foot is holding its target.
            tick_time_s: Wall time of the control tick [s] (defaults to its own timing).
        """
        sim = self.sim
        now = sim.time_s
        dt = now - self._last_s  # one control period, whatever the physics step
        self._last_s = now
        if foot_error_m is not None:
            self.tracking_errors.append(foot_error_m)
            if holding:
                self.holding_errors.append(foot_error_m)
        stance = self._stance
        for i, leg in enumerate(LEGS):
            stance[i] = leg in stance_legs
        stats = self._stats
        loaded = _feet(stance, sim.foot_sliding_velocity_array(self._sliding),
                       sim.foot_position_array(self._positions),
                       sim.foot_contact_force_array(self._forces), dt, self._slid,
                       self._ground, self._loaded, stats)
        if loaded >= 3:
            com = sim.data.subtree_com[1]
            margin = shrunk_signed_distance(self._loaded, com, count=loaded)
            self.min_margin = min(self.min_margin, margin)
        q, _ = sim.state()
        x, y, height = float(q[3]), float(q[4]), float(q[2])
        # Tilt: angle between the base's z axis and the world's.
        cos_tilt = 1.0 - 2.0 * (x * x + y * y)
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, cos_tilt))))
        self.max_tilt = max(self.max_tilt, tilt)
        if height < 0.15 or tilt > 45.0:
            self.fell = True
        tau = np.asarray(out.tau, dtype=float)
        _torques(tau, self._tau_prev, self.effort_limit, self.ticks > 0, stats)
        (self.sliding_max, self.travel_max, self.min_force, self.max_torque_fraction,
         self.max_jump) = stats.tolist()
        self.ticks += 1
        if not out.ok:
            self.failures += 1
        elapsed = tick_time_s if tick_time_s is not None else out.timings.get("total", 0.0)
        self.tick_times.append(elapsed)

    def summary(self, wall_time_s: float) -> EpisodeSummary:
        """Condense the episode; ``wall_time_s`` is the wall time the whole run took."""
        def rms(values: list[float]) -> float:
            return float(np.sqrt(np.mean(np.square(values)))) * 1e3 if values else 0.0

        def peak(values: list[float]) -> float:
            return float(np.max(values)) * 1e3 if values else 0.0

        times = np.array(self.tick_times) * 1e6 if self.tick_times else np.zeros(1)
        duration = self.sim.time_s - self.start_s
        return EpisodeSummary(
            duration_s=duration, ticks=self.ticks,
            raised_foot_rms_mm=rms(self.tracking_errors),
            raised_foot_max_mm=peak(self.tracking_errors),
            holding_rms_mm=rms(self.holding_errors), holding_max_mm=peak(self.holding_errors),
            stance_sliding_max_mm=self.sliding_max * 1e3,
            stance_travel_max_mm=self.travel_max * 1e3,
            min_stance_normal_force_n=self.min_force if self.min_force < math.inf else 0.0,
            min_com_margin_mm=self.min_margin * 1e3 if self.min_margin < math.inf else 0.0,
            max_base_tilt_deg=self.max_tilt, max_torque_fraction=self.max_torque_fraction,
            max_torque_jump_nm=self.max_jump, qp_failures=self.failures,
            tick_median_us=float(np.median(times)), tick_p99_us=float(np.percentile(times, 99)),
            tick_max_us=float(np.max(times)),
            real_time_factor=duration / wall_time_s if wall_time_s > 0 else math.inf,
            fell=self.fell,
        )
