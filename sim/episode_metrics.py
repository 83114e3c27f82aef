"""Quality metrics of a closed-loop episode, measured in MuJoCo tick by tick."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from sim.simulator import Go2Simulator
from wbc.control_output import ControlOutput
from wbc.description import LEGS
from wbc.support_polygon import SupportPolygon

#: A foot carrying less than this [N] counts as unloaded.
LOADED_FORCE_N = 1.0


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
        self._sliding = {leg: np.zeros(2) for leg in LEGS}
        self._ground = sim.foot_positions()
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
        self._tau_prev: np.ndarray | None = None
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
        self.ticks += 1
        dt = sim.time_s - self._last_s  # one control period, whatever the physics step
        self._last_s = sim.time_s
        if foot_error_m is not None:
            self.tracking_errors.append(foot_error_m)
            if holding:
                self.holding_errors.append(foot_error_m)
        sliding = sim.foot_sliding_velocities()
        forces = sim.foot_contact_forces()
        positions = sim.foot_positions()
        for leg in LEGS:
            if leg in stance_legs:
                self._sliding[leg] += sliding[leg] * dt
                self.sliding_max = max(self.sliding_max, float(np.linalg.norm(self._sliding[leg])))
                travel = np.linalg.norm(positions[leg][:2] - self._ground[leg][:2])
                self.travel_max = max(self.travel_max, float(travel))
                self.min_force = min(self.min_force, float(forces[leg][2]))
            else:  # a foot that leaves the ground starts afresh when it lands
                self._sliding[leg][:] = 0.0
                self._ground[leg] = positions[leg]
        q, _ = sim.state()
        loaded = [positions[leg][:2] for leg in LEGS if forces[leg][2] > LOADED_FORCE_N]
        com = sim.data.subtree_com[1][:2]
        if len(loaded) >= 3:
            margin = SupportPolygon.signed_distance(np.array(loaded), com)
            self.min_margin = min(self.min_margin, margin)
        x, y, z, w = q[3:7]
        # Tilt: angle between the base's z axis and the world's.
        cos_tilt = 1.0 - 2.0 * (x * x + y * y)
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, cos_tilt))))
        self.max_tilt = max(self.max_tilt, tilt)
        if q[2] < 0.15 or tilt > 45.0:
            self.fell = True
        tau = out.tau
        self.max_torque_fraction = max(self.max_torque_fraction,
                                       float(np.max(np.abs(tau) / self.effort_limit)))
        if self._tau_prev is not None:
            self.max_jump = max(self.max_jump, float(np.max(np.abs(tau - self._tau_prev))))
        self._tau_prev = tau
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
