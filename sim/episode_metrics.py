"""Quality metrics of a closed-loop episode, measured in MuJoCo tick by tick."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numba
import numpy as np

from sim.simulator import Go2Simulator
from wbc.controller.control_output import ControlOutput
from wbc.model.description import LEGS
from wbc.model.support_polygon import shrunk_signed_distance

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


#: What :class:`EstimateErrors` accumulates (``stats``'s entries).
_N, _V2, _VMAX, _H2, _HMAX, _ROLL, _PITCH, _DRIFT, _DRIFT_MAX, _YAW, _YAW_MAX, _H_FIRST, _H_LAST = (
    range(13))


@numba.njit(cache=True)
def _gravity_angles(quat):  # pragma: no cover - compiled
    """Roll and pitch [rad] of the base from a Pinocchio quaternion (x, y, z, w): the angles
    of the world's "up" seen in the base frame (yaw does not enter)."""
    x, y, z, w = quat[0], quat[1], quat[2], quat[3]
    gx = 2.0 * (x * z - y * w)
    gy = 2.0 * (y * z + x * w)
    gz = 1.0 - 2.0 * (x * x + y * y)
    return math.atan2(gy, gz), math.atan2(-gx, math.sqrt(gy * gy + gz * gz))


@numba.njit(cache=True)
def _yaw(quat):  # pragma: no cover - compiled
    x, y, z, w = quat[0], quat[1], quat[2], quat[3]
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


@numba.njit(numba.void(_F64[::1], _F64[::1], _F64[::1], _F64[::1], _F64[::1], _F64[::1]),
            cache=True)
def _estimate_errors(q_est, v_est, q_true, v_true, alignment, stats):  # pragma: no cover
    """Accumulate one tick's estimation errors into ``stats`` (see :class:`EstimateErrors`).

    ``alignment`` is ``(cos, sin, tx, ty, tz, yaw offset)``: the estimator's world frame
    carried into the simulator's (a yaw and a translation fixed when measuring began).
    """
    c, s, tx, ty = alignment[0], alignment[1], alignment[2], alignment[3]
    v2 = 0.0
    for k in range(3):  # base-frame linear velocity: no frame alignment needed
        v2 += (v_est[k] - v_true[k]) ** 2
    stats[_N] += 1.0
    stats[_V2] += v2
    stats[_VMAX] = max(stats[_VMAX], math.sqrt(v2))
    height = q_est[2] - q_true[2]
    stats[_H2] += height * height
    stats[_HMAX] = max(stats[_HMAX], abs(height))
    if stats[_N] == 1.0:
        stats[_H_FIRST] = height
    stats[_H_LAST] = height
    roll_est, pitch_est = _gravity_angles(q_est[3:7])
    roll_true, pitch_true = _gravity_angles(q_true[3:7])
    stats[_ROLL] = max(stats[_ROLL], abs(roll_est - roll_true))
    stats[_PITCH] = max(stats[_PITCH], abs(pitch_est - pitch_true))
    dx = c * q_est[0] - s * q_est[1] + tx - q_true[0]
    dy = s * q_est[0] + c * q_est[1] + ty - q_true[1]
    drift = math.sqrt(dx * dx + dy * dy)
    stats[_DRIFT] = drift
    stats[_DRIFT_MAX] = max(stats[_DRIFT_MAX], drift)
    yaw = _yaw(q_est[3:7]) + alignment[5] - _yaw(q_true[3:7])
    yaw = (yaw + math.pi) % (2.0 * math.pi) - math.pi
    stats[_YAW] = yaw
    stats[_YAW_MAX] = max(stats[_YAW_MAX], abs(yaw))


class FrameAlignment:
    """The estimator's world frame carried into the simulator's, fixed at one instant.

    A state estimator's world has its own origin and heading (this library's starts with the
    base's heading at zero, and its yaw drifts as a magnetometer-free IMU's does). Targets
    the controller was given in it, and its positions, are compared with the simulator's
    through the yaw and translation that map the estimated base onto the true one at that
    instant (goal start, for a goal's metrics).

    Args:
        q_estimate: The estimated configuration (19,) at that instant.
        q_true: The true configuration (19,) at the same instant.
    """

    def __init__(self, q_estimate: np.ndarray, q_true: np.ndarray):
        yaw = _yaw(np.ascontiguousarray(q_true[3:7])) - _yaw(
            np.ascontiguousarray(q_estimate[3:7]))
        c, s = math.cos(yaw), math.sin(yaw)
        self.rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        self.translation = np.asarray(q_true[:3], dtype=float) - self.rotation @ q_estimate[:3]
        #: ``(cos, sin, tx, ty, tz, yaw)`` for the compiled error kernel.
        self.vector = np.array([c, s, *self.translation, yaw])

    def point_to_true(self, point: np.ndarray) -> np.ndarray:
        """A point [m] of the estimator's world, in the simulator's."""
        return self.rotation @ point + self.translation


class EstimateErrors:
    """The state estimate against the simulator's truth, tick by tick.

    Args:
        alignment: The frame alignment fixed when measuring began.
    """

    def __init__(self, alignment: FrameAlignment):
        self.alignment = alignment
        self.stats = np.zeros(13)

    def record(self, q_estimate: np.ndarray, v_estimate: np.ndarray, q_true: np.ndarray,
               v_true: np.ndarray) -> None:
        """One tick's estimate and the truth at the same instant (Pinocchio conventions)."""
        _estimate_errors(q_estimate, v_estimate, q_true, v_true, self.alignment.vector,
                         self.stats)

    def summary(self) -> dict[str, float]:
        """Velocity error RMS and max [m/s], height error RMS, max and drift [mm], roll and
        pitch error max [deg], horizontal drift at the end and max [mm], yaw drift at the end
        and max [deg]."""
        st = self.stats
        n = max(st[_N], 1.0)
        return {
            "velocity_rms_m_s": math.sqrt(st[_V2] / n), "velocity_max_m_s": st[_VMAX],
            "height_rms_mm": 1e3 * math.sqrt(st[_H2] / n), "height_max_mm": 1e3 * st[_HMAX],
            "height_drift_mm": 1e3 * abs(st[_H_LAST] - st[_H_FIRST]),
            "roll_max_deg": math.degrees(st[_ROLL]), "pitch_max_deg": math.degrees(st[_PITCH]),
            "horizontal_drift_mm": 1e3 * st[_DRIFT],
            "horizontal_drift_max_mm": 1e3 * st[_DRIFT_MAX],
            "yaw_drift_deg": math.degrees(st[_YAW]),
            "yaw_drift_max_deg": math.degrees(st[_YAW_MAX]),
        }


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
    #: Ticks the controller's QP failed while the loop controlled the robot.
    qp_failures: int
    tick_median_us: float
    tick_p99_us: float
    tick_max_us: float
    real_time_factor: float
    fell: bool
    #: Ticks the loop damped the motors without a trustworthy state (no QP ran:
    #: :mod:`actions.robot.state_fallback`), not counted as QP failures.
    no_state_ticks: int = 0
    #: The state estimate against the truth (all 0 when the controller read the truth):
    #: base linear velocity error [m/s], height error [mm], roll and pitch error [deg],
    #: horizontal drift [mm] and yaw drift [deg] since measuring began.
    estimate_velocity_rms_m_s: float = 0.0
    estimate_velocity_max_m_s: float = 0.0
    estimate_height_rms_mm: float = 0.0
    estimate_height_max_mm: float = 0.0
    estimate_height_drift_mm: float = 0.0
    estimate_roll_max_deg: float = 0.0
    estimate_pitch_max_deg: float = 0.0
    estimate_horizontal_drift_mm: float = 0.0
    estimate_horizontal_drift_max_mm: float = 0.0
    estimate_yaw_drift_deg: float = 0.0
    estimate_yaw_drift_max_deg: float = 0.0

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
        self.no_state_ticks = 0
        self.tick_times: list[float] = []
        self.fell = False
        self.ticks = 0
        #: The state estimate's accuracy, when the controller reads an estimate (fed by
        #: the caller, who knows the estimate and the truth at the same instant).
        self.estimate_errors: EstimateErrors | None = None

    def record(self, out: ControlOutput, *, stance_legs: list[str],
               foot_error_m: float | None = None, holding: bool = False,
               tick_time_s: float | None = None, controlling: bool = True) -> None:
        """Measure one tick.

        Args:
            out: The controller's output this tick.
            stance_legs: Legs that must stay put (fully loaded stance feet).
            foot_error_m: Raised-foot position error [m], when a foot tracks a target.
            holding: The raised foot is holding its target.
            tick_time_s: Wall time of the control tick [s] (defaults to its own timing).
            controlling: The loop controlled the robot this tick; a safe command while it did
                not (no trustworthy state) counts in ``no_state_ticks``, not as a QP failure.
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
            if controlling:
                self.failures += 1
            else:
                self.no_state_ticks += 1
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
            fell=self.fell, no_state_ticks=self.no_state_ticks,
            **({} if self.estimate_errors is None else {
                f"estimate_{k}": v for k, v in self.estimate_errors.summary().items()}),
        )
