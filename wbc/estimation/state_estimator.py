"""The floating base's state from what a GO2 measures: IMU, joint encoders, foot contact.

:class:`StateEstimator` turns one :class:`wbc.SensorRecord` per control tick, and the
controller's contact schedule, into the controller's ``(q, v)``:

- **Orientation and angular velocity** come from the IMU. The robot's attitude filter gives
  the orientation; a complementary filter follows it (time constant
  ``orientation_time_constant_s``) while integrating the gyroscope, whose bias it learns from
  the difference (``gyro_bias_time_constant_s``). So the orientation keeps coming, from the
  gyroscope alone, when a quaternion is missing or corrupt, and the angular velocity is the
  gyroscope's less its bias. The estimator's world frame has the yaw of the first record at
  zero.
- **Position and linear velocity** come from a linear Kalman filter (the one of MIT's
  Cheetah-Software, legged_control and unitree_guide): 18 states, the IMU site's position
  and velocity and the four feet's positions, world frame; it predicts with the
  accelerometer and corrects with each stance foot's kinematics (its position relative to
  the IMU, its velocity being zero where it touches the floor, its height above a flat floor
  at z = 0). The feet are spheres that roll: a stance foot's centre moves at
  ``omega_foot x (0, 0, r)``, which the prediction carries and the velocity measurement
  subtracts. With the orientation known, the filter splits exactly into three independent
  6-state filters, one per world axis, each updated one scalar measurement at a time: about
  2 us a tick, compiled, with no allocation.
- **Contact**: each foot's weight in the correction is the schedule's (1 for a loaded stance
  foot, ramping to 0 as the controller unloads it, 0 in swing) times the foot-force sensor's
  verdict (a count above ``foot_force_on`` turns contact on, below ``foot_force_off`` off).
  A foot's measurement noise grows ``swing_noise_scale`` times as its weight goes from 1 to
  0; a foot below ``min_contact_weight`` follows the kinematics freely. Without foot sensors
  (``use_foot_force=False``, or a sensor distrusted) the schedule alone decides.

Faults: a non-finite or non-unit quaternion, a non-finite gyroscope, accelerometer or
joint reading, a repeated (stale) sample, no sample at all, a stance foot's sensor stuck on
one value, a foot sensor at full scale. The estimate reports what it distrusts
(:attr:`StateEstimate.faults`), goes on with the rest, and says when it has had no
trustworthy sample for longer than ``trust_timeout_s`` (:attr:`StateEstimate.usable`): the
control loop then sends the controller's safe command. The README's "What it measures"
section has the measurements behind the choices (this filter against the contact-aided
invariant EKF, :class:`wbc.InvariantEkf`, the default).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import Any, ClassVar

import numba
import numpy as np

from wbc.core.compiled_call import bind_compiled
from wbc.core.errors import ConfigurationError
from wbc.core.quaternion_kernels import (
    quat_exp,
    quat_log,
    quat_multiply,
    quat_normalize,
    quat_rotation,
    quat_yaw,
)
from wbc.core.validation import as_float, as_vector, known_fields_only
from wbc.model.description import FOOT_RADIUS_M, LEGS, Go2Description
from wbc.model.leg_kinematics import LegKinematics, leg_kinematics
from wbc.robot_io.sensor_record import SensorRecord

# Fault flags of one tick (the kernel's return value).
STALE, NO_DATA, QUATERNION_NON_FINITE, QUATERNION_NOT_UNIT = 1, 2, 4, 8
GYRO_BAD, ACCEL_BAD, JOINTS_BAD, FOOT_SENSOR = 16, 32, 64, 128
QUATERNION_TIMEOUT = 256
#: Flags that make a sample untrustworthy (the others are worked around).
UNTRUSTED = STALE | NO_DATA | GYRO_BAD | JOINTS_BAD | QUATERNION_TIMEOUT
# Why a foot sensor is distrusted.
FOOT_OK, FOOT_STUCK, FOOT_SATURATED, FOOT_NON_FINITE = 0, 1, 2, 3
#: The flags carry each foot's reason, two bits a foot (``LEGS`` order), from this bit on.
FOOT_REASON_SHIFT = 16
_FOOT_REASONS = {FOOT_STUCK: "stuck at {value:g}", FOOT_SATURATED: "at full scale ({value:g})",
                 FOOT_NON_FINITE: "non-finite ({value})"}

# The kernel's state vector: orientation, gyro bias, yaw alignment, last good readings,
# bookkeeping.
_QUAT, _BIAS, _ALIGN, _OMEGA, _ACCEL = 0, 4, 7, 11, 14
_QUAT_AGE_S = 17
_STATE_SIZE = 18
#: Scratch space of the tick's kernel.
_WORK_SIZE = 136
#: ``clock``'s entry of the time without a trusted sample (see :func:`check_sample`).
_UNTRUSTED_S = 2
_GRAVITY = 9.81


@dataclass(frozen=True)
class SensorTrustConfig:
    """What every estimator here shares: which readings it trusts, how it weighs the feet.

    Attributes:
        quaternion_tolerance: Largest ``| |quat| - 1 |`` of a quaternion taken as unit.
        quaternion_timeout_s: Time [s] on the gyroscope alone before the orientation is
            no longer trusted (an estimator whose orientation needs no quaternion ignores
            it).
        foot_position_noise_m: Noise of a foot's position from the kinematics [m].
        swing_noise_scale: How much a foot's measurement noise grows at zero contact weight.
        min_contact_weight: Below this weight a foot follows the kinematics freely.
        full_trust_force_n: A stance foot whose normal-force bound [N] is at least this
            has the schedule's full weight (the bound ramps down as a foot is unloaded).
        use_foot_force: Fuse the foot-force counts with the schedule (off: schedule only,
            for robots or simulators without foot sensors).
        foot_force_on: Count above which a foot turns to contact.
        foot_force_off: Count below which it turns to no contact.
        foot_force_full_scale: The sensor's highest count: a reading there is saturated.
        foot_sensor_stuck_s: A stance foot's sensor whose count does not change for this
            long [s] is stuck (a loaded foot's live sensor always changes: its load and its
            noise do).
        foot_sensor_recover_s: It is trusted again after this long [s] of changing,
            in-range readings.
        trust_timeout_s: Time [s] without a trustworthy sample (fresh, finite joints and
            gyroscope) after which the estimate is not usable and the loop sends the
            controller's safe command.
        foot_radius_m: Radius of the foot spheres [m].
    """

    #: Valid range of each of the subclass's own numeric fields (low exclusive unless 0).
    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {}
    #: The numbers the subclass's kernel reads, in its order.
    _PARAMS: ClassVar[tuple[str, ...]] = ()

    quaternion_tolerance: float = 0.01
    quaternion_timeout_s: float = 1.0
    foot_position_noise_m: float = 2e-3
    swing_noise_scale: float = 100.0
    min_contact_weight: float = 0.02
    full_trust_force_n: float = 30.0
    use_foot_force: bool = True
    foot_force_on: float = 60.0
    foot_force_off: float = 40.0
    foot_force_full_scale: float = 1000.0
    foot_sensor_stuck_s: float = 0.05
    foot_sensor_recover_s: float = 0.5
    trust_timeout_s: float = 0.01
    foot_radius_m: float = FOOT_RADIUS_M

    def __post_init__(self) -> None:
        for name, (low, high) in {**_SHARED_RANGES, **self._RANGES}.items():
            as_float(name, getattr(self, name), low=low, high=high, low_inclusive=low == 0.0)
        if not isinstance(self.use_foot_force, bool):
            raise ConfigurationError(
                f"use_foot_force: expected true or false, received {self.use_foot_force!r}")
        if self.foot_force_off >= self.foot_force_on:
            raise ConfigurationError(
                f"foot_force_off: expected less than foot_force_on ({self.foot_force_on:g}), "
                f"received {self.foot_force_off:g}")
        if self.foot_force_full_scale <= self.foot_force_on:
            raise ConfigurationError(
                f"foot_force_full_scale: expected more than foot_force_on "
                f"({self.foot_force_on:g}), received {self.foot_force_full_scale:g}")

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Every field's name."""
        return tuple(f.name for f in fields(cls))

    def _vector(self) -> np.ndarray:
        """The kernel's numbers: the subclass's ``_PARAMS``, then :data:`CONTACT_PARAMS`."""
        return np.array([getattr(self, name) for name in (*self._PARAMS, *CONTACT_PARAMS)],
                        dtype=float)


#: The contact fusion's fields, the last of every estimator's kernel vector, in this order.
CONTACT_PARAMS = ("full_trust_force_n", "use_foot_force", "foot_force_on", "foot_force_off",
                  "foot_force_full_scale", "foot_sensor_stuck_s", "foot_sensor_recover_s")

#: Valid range of each shared numeric field (a 0 lower bound is inclusive, others exclusive).
_SHARED_RANGES: dict[str, tuple[float, float]] = {
    "quaternion_tolerance": (1e-6, 0.5), "quaternion_timeout_s": (1e-3, 60.0),
    "foot_position_noise_m": (1e-9, 1.0), "swing_noise_scale": (1.0, 1e6),
    "min_contact_weight": (0.0, 1.0), "full_trust_force_n": (1e-3, 1e4),
    "foot_force_on": (-32768.0, 32767.0), "foot_force_off": (-32768.0, 32767.0),
    "foot_force_full_scale": (-32768.0, 32767.0), "foot_sensor_stuck_s": (1e-3, 10.0),
    "foot_sensor_recover_s": (0.0, 60.0), "trust_timeout_s": (0.0, 10.0),
    "foot_radius_m": (0.0, 0.1),
}


@known_fields_only("estimator parameter")
@dataclass(frozen=True)
class EstimatorConfig(SensorTrustConfig):
    """Every number of the linear estimator, validated (an error names the field and its
    range); the shared ones are :class:`SensorTrustConfig`'s.

    Attributes:
        orientation_time_constant_s: How fast [s] the orientation follows the IMU's
            quaternion (the gyroscope carries it in between).
        gyro_bias_time_constant_s: How fast [s] the gyroscope bias is learnt from it.
        position_process_noise: Random walk of the IMU's position [m/sqrt(s)].
        velocity_process_noise: Of its velocity (what the accelerometer misses)
            [m/s/sqrt(s)].
        foot_process_noise: Of a stance foot's position (slip, rolling the model misses)
            [m/sqrt(s)].
        foot_velocity_noise_m_s: Noise of the body's velocity from a stance foot [m/s].
        foot_height_noise_m: Noise of a stance foot's height above the floor [m].
    """

    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "orientation_time_constant_s": (1e-4, 100.0), "gyro_bias_time_constant_s": (1e-3, 1e4),
        "position_process_noise": (1e-9, 10.0), "velocity_process_noise": (1e-9, 100.0),
        "foot_process_noise": (1e-9, 10.0), "foot_velocity_noise_m_s": (1e-9, 10.0),
        "foot_height_noise_m": (1e-9, 1.0),
    }
    _PARAMS: ClassVar[tuple[str, ...]] = (
        "orientation_time_constant_s", "gyro_bias_time_constant_s", "quaternion_tolerance",
        "quaternion_timeout_s", "position_process_noise", "velocity_process_noise",
        "foot_process_noise", "foot_position_noise_m", "foot_velocity_noise_m_s",
        "foot_height_noise_m", "swing_noise_scale", "min_contact_weight", "foot_radius_m")

    orientation_time_constant_s: float = 0.05
    gyro_bias_time_constant_s: float = 10.0
    position_process_noise: float = 1e-3
    velocity_process_noise: float = 0.1
    foot_process_noise: float = 1e-3
    foot_velocity_noise_m_s: float = 0.03
    foot_height_noise_m: float = 2e-3


# ----------------------------------------------------------------------------- the kernel


@numba.njit(cache=True)
def _scalar_update(x, P, plus, minus, measured, variance, gain, projected):  # pragma: no cover
    """Kalman update of one axis' filter with ``x[plus] - x[minus] = measured`` (``minus``
    -1: ``x[plus] = measured``), measurement variance ``variance``."""
    n = x.shape[0]
    for r in range(n):
        projected[r] = P[r, plus] - P[r, minus] if minus >= 0 else P[r, plus]
    innovation = measured - (x[plus] - x[minus] if minus >= 0 else x[plus])
    s = projected[plus] - (projected[minus] if minus >= 0 else 0.0) + variance
    for r in range(n):
        gain[r] = projected[r] / s
        x[r] += gain[r] * innovation
    for r in range(n):
        for c in range(n):
            P[r, c] -= gain[r] * projected[c]


@numba.njit(cache=True)
def check_sample(fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, clock,
                 dt_nominal, quat_tol):  # pragma: no cover - compiled
    """Which parts of this tick's sample can be used; the time step.

    Args:
        fresh: A sample arrived (``False``: none this period).
        tick, stamp_s: Its counter and stamp [s].
        quat_in, gyro_in, accel_in, q_in, dq_in: Its IMU and joint readings.
        clock: In/out: ``(last tick, last stamp [s], untrusted time [s], time predicted
            since the last sample [s])``.
        dt_nominal: The control period [s], used when the stamps do not give the step.
        quat_tol: Largest ``| |quat| - 1 |`` of a usable quaternion.

    Returns:
        ``(flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok)``: the fault flags so far,
        the time step [s], a new sample (not repeated), and each part's usability.
    """
    flags = 0
    dt = dt_nominal
    new = fresh
    if not fresh:
        flags |= NO_DATA
    elif tick == clock[0]:
        flags |= STALE
        new = False
    if new:
        # The step from the last sample, less what was predicted since without one.
        elapsed = stamp_s - clock[1]
        if 0.0 < elapsed < 0.1:
            dt = max(0.0, elapsed - clock[3])
        clock[0] = tick
        clock[1] = stamp_s
        clock[3] = 0.0
    else:
        clock[3] += dt
    joints_ok = new
    if new:
        for j in range(12):
            if not (math.isfinite(q_in[j]) and math.isfinite(dq_in[j])):
                joints_ok = False
        if not joints_ok:
            flags |= JOINTS_BAD
    gyro_ok = new and math.isfinite(gyro_in[0]) and math.isfinite(gyro_in[1]) and \
        math.isfinite(gyro_in[2])
    if new and not gyro_ok:
        flags |= GYRO_BAD
    accel_ok = new and math.isfinite(accel_in[0]) and math.isfinite(accel_in[1]) and \
        math.isfinite(accel_in[2])
    if new and not accel_ok:
        flags |= ACCEL_BAD
    quat_ok = False
    if new:
        norm = math.sqrt(quat_in[0] ** 2 + quat_in[1] ** 2 + quat_in[2] ** 2 + quat_in[3] ** 2)
        if not math.isfinite(norm):
            flags |= QUATERNION_NON_FINITE
        elif abs(norm - 1.0) > quat_tol:
            flags |= QUATERNION_NOT_UNIT
        else:
            quat_ok = True
    return flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok


@numba.njit(cache=True)
def account_trust(flags, dt, clock):  # pragma: no cover - compiled
    """Add ``dt`` [s] to the untrusted time ``clock[2]`` if the tick's flags make it
    untrustworthy, else reset it."""
    if flags & UNTRUSTED:
        clock[2] += dt
    else:
        clock[2] = 0.0


@numba.njit(cache=True)
def contact_weights(new, dt, force_in, schedule, full_force, use_force, force_on, force_off,
                    force_full, stuck_s, recover_s, foot_contact, foot_same_s, foot_good_s,
                    foot_reason, foot_last, weight):  # pragma: no cover - compiled
    """Each foot's contact weight: the schedule, fused with its foot-force sensor.

    The schedule's weight is the foot's normal-force bound over ``full_force`` (clipped to
    [0, 1]); the sensor's verdict is a hysteresis between ``force_off`` and ``force_on``
    counts. A sensor at full scale, non-finite, or (on a scheduled stance foot) repeating
    one reading for ``stuck_s`` [s] is distrusted until it has read changing, in-range
    values for ``recover_s`` [s]; the schedule alone then decides for that foot.

    Returns:
        :data:`FOOT_SENSOR` if a foot sensor is distrusted, else 0, with each foot's reason
        in two bits from :data:`FOOT_REASON_SHIFT`. ``foot_*`` are the sensors' state
        (in/out), ``weight`` (4,) the output.
    """
    flags = 0
    for i in range(4):
        scheduled = min(1.0, max(0.0, schedule[i] / full_force))
        if new:
            value = force_in[i]
            if not math.isfinite(value):
                foot_reason[i] = FOOT_NON_FINITE
                foot_good_s[i] = 0.0
            else:
                # A loaded foot's live sensor never repeats a reading for long (its load and
                # its noise change it); a foot in the air may well read a steady zero load.
                if value == foot_last[i] and scheduled > 0.0:
                    foot_same_s[i] += dt
                else:
                    foot_same_s[i] = 0.0
                foot_last[i] = value
                if value >= force_full:
                    foot_reason[i] = FOOT_SATURATED
                    foot_good_s[i] = 0.0
                elif foot_same_s[i] >= stuck_s:
                    foot_reason[i] = FOOT_STUCK
                    foot_good_s[i] = 0.0
                elif foot_reason[i] != FOOT_OK:
                    foot_good_s[i] += dt
                    if foot_good_s[i] >= recover_s:
                        foot_reason[i] = FOOT_OK
                if value > force_on:
                    foot_contact[i] = 1.0
                elif value < force_off:
                    foot_contact[i] = 0.0
        if foot_reason[i] != FOOT_OK:
            flags |= FOOT_SENSOR | (foot_reason[i] << (FOOT_REASON_SHIFT + 2 * i))
        if use_force and foot_reason[i] == FOOT_OK:
            weight[i] = scheduled * foot_contact[i]
        else:
            weight[i] = scheduled
    return flags


@numba.njit(cache=True)
def legs_and_contacts(joints_ok, new, dt, q_in, dq_in, force_in, schedule, params, rotations,
                      translations, axes, foot_offsets, foot_position, foot_jacobian,
                      foot_angular_jacobian, legs_work, joint_q, joint_dq, foot_contact,
                      foot_same_s, foot_good_s, foot_reason, foot_last,
                      weight):  # pragma: no cover - compiled
    """The joints (kept when usable), the legs' kinematics and each foot's contact weight
    (:func:`contact_weights`); the contact flags.

    ``params`` is the estimator's config vector; the contact fields are read from its end
    (:data:`CONTACT_PARAMS`, every estimator's config ends with them in that order).
    """
    if joints_ok:
        for j in range(12):
            joint_q[j] = q_in[j]
            joint_dq[j] = dq_in[j]
        leg_kinematics(joint_q, rotations, translations, axes, foot_offsets, foot_position,
                       foot_jacobian, foot_angular_jacobian, legs_work)
    end = params.shape[0]
    return contact_weights(new, dt, force_in, schedule, params[end - 7], params[end - 6] > 0.5,
                           params[end - 5], params[end - 4], params[end - 3], params[end - 2],
                           params[end - 1], foot_contact, foot_same_s, foot_good_s,
                           foot_reason, foot_last, weight)


@numba.njit(cache=True)
def foot_motion(rotation, omega, joint_dq, origin, foot_position, foot_jacobian,
                foot_angular_jacobian, radius, relative, velocity, rolling,
                work):  # pragma: no cover - compiled
    """Each foot's kinematics in the world's orientation, relative to a point of the base.

    Args:
        rotation: The base's orientation ``R_world_base`` (3, 3).
        omega: The base's angular velocity, base frame [rad/s].
        joint_dq: Joint velocities [rad/s] (12,), description order.
        origin: The point of the base [m] (the IMU), base frame.
        foot_position, foot_jacobian, foot_angular_jacobian: :class:`LegKinematics`' outputs.
        radius: The foot spheres' radius [m].
        relative: Out (4, 3): each foot centre minus the point, world orientation [m].
        velocity: Out (4, 3): the point's world velocity [m/s] if the foot's sphere rolls
            on the floor without slipping.
        rolling: Out (4, 3): the foot centre's world velocity as its sphere rolls
            (``omega_foot x (0, 0, radius)``) [m/s].
        work: Scratch space (4, 3).
    """
    body, spin, rel_v, world_spin = work[0], work[1], work[2], work[3]
    for i in range(4):
        for r in range(3):
            body[r] = foot_position[i, r] - origin[r]
        for r in range(3):
            relative[i, r] = (rotation[r, 0] * body[0] + rotation[r, 1] * body[1]
                              + rotation[r, 2] * body[2])
        # The foot centre's velocity relative to the point, base frame: omega x body + J dq.
        rel_v[0] = omega[1] * body[2] - omega[2] * body[1]
        rel_v[1] = omega[2] * body[0] - omega[0] * body[2]
        rel_v[2] = omega[0] * body[1] - omega[1] * body[0]
        for r in range(3):
            spin[r] = omega[r]
            for k in range(3):
                rel_v[r] += foot_jacobian[i, r, k] * joint_dq[3 * i + k]
                spin[r] += foot_angular_jacobian[i, r, k] * joint_dq[3 * i + k]
        for r in range(3):
            world_spin[r] = (rotation[r, 0] * spin[0] + rotation[r, 1] * spin[1]
                             + rotation[r, 2] * spin[2])
        rolling[i, 0] = world_spin[1] * radius
        rolling[i, 1] = -world_spin[0] * radius
        rolling[i, 2] = 0.0
        for r in range(3):
            velocity[i, r] = rolling[i, r] - (rotation[r, 0] * rel_v[0]
                                              + rotation[r, 1] * rel_v[1]
                                              + rotation[r, 2] * rel_v[2])


@numba.njit(cache=True)
def _estimate(fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, force_in,
              schedule, dt_nominal, params, imu_offset, rotations, translations, axes,
              foot_offsets, foot_position, foot_jacobian, foot_angular_jacobian, clock, state,
              x, P, foot_contact, foot_same_s, foot_good_s, foot_reason, foot_last, joint_q,
              joint_dq, q_out, v_out, weight, work):  # pragma: no cover - compiled
    """One tick of the estimator (see the module docstring); returns the fault flags.

    ``state`` holds the orientation (w, x, y, z), the gyro bias, the yaw alignment, the last
    good angular velocity and specific force, and the quaternion's age; ``x`` (3, 6) and
    ``P`` (3, 6, 6) are the three axes' filters: ``[IMU position, IMU velocity, feet 0..3]``.
    ``work`` (:data:`_WORK_SIZE`) is scratch space: the tick allocates nothing.
    """
    (tau_q, tau_b, quat_tol, quat_timeout, sigma_p, sigma_v, sigma_f, sigma_pos, sigma_vel,
     sigma_h, swing_scale, min_weight, radius) = (
        params[0], params[1], params[2], params[3], params[4], params[5], params[6],
        params[7], params[8], params[9], params[10], params[11], params[12])
    flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok = check_sample(
        fresh, tick, stamp_s, quat_in, gyro_in, accel_in, q_in, dq_in, clock, dt_nominal,
        quat_tol)
    # --- orientation: gyroscope, pulled towards the IMU's quaternion
    quat = state[_QUAT:_QUAT + 4]
    bias = state[_BIAS:_BIAS + 3]
    omega = state[_OMEGA:_OMEGA + 3]
    if gyro_ok:
        for k in range(3):
            omega[k] = gyro_in[k] - bias[k]
    step, product, measured, inverse = work[0:4], work[4:8], work[8:12], work[12:16]
    error, world_accel = work[16:19], work[19:22]
    gain_vector, projected = work[22:28], work[28:34]
    rotation = work[34:43].reshape((3, 3))
    relative = work[43:55].reshape((4, 3))
    velocity = work[55:67].reshape((4, 3))
    rolling = work[67:79].reshape((4, 3))
    legs_work = work[79:115].reshape((4, 3, 3))
    motion_work = work[115:127].reshape((4, 3))
    output_work = work[127:136].reshape((3, 3))
    quat_exp(omega[0] * dt, omega[1] * dt, omega[2] * dt, step)
    quat_multiply(quat, step, product)
    quat[:] = product
    if quat_ok:
        quat_multiply(state[_ALIGN:_ALIGN + 4], quat_in, measured)
        quat_normalize(measured)
        inverse[0] = quat[0]
        for k in range(1, 4):
            inverse[k] = -quat[k]
        quat_multiply(inverse, measured, product)
        quat_log(product, error)
        gain = min(1.0, dt / tau_q)
        quat_exp(gain * error[0], gain * error[1], gain * error[2], step)
        quat_multiply(quat, step, product)
        quat[:] = product
        for k in range(3):
            bias[k] -= error[k] * dt / (tau_q * tau_b)
        state[_QUAT_AGE_S] = 0.0
    else:
        state[_QUAT_AGE_S] += dt
        if state[_QUAT_AGE_S] > quat_timeout:
            flags |= QUATERNION_TIMEOUT
    quat_normalize(quat)
    quat_rotation(quat, rotation)
    # --- legs and contacts
    flags |= legs_and_contacts(joints_ok, new, dt, q_in, dq_in, force_in, schedule, params,
                               rotations, translations, axes, foot_offsets, foot_position,
                               foot_jacobian, foot_angular_jacobian, legs_work, joint_q,
                               joint_dq, foot_contact, foot_same_s, foot_good_s, foot_reason,
                               foot_last, weight)
    foot_motion(rotation, omega, joint_dq, imu_offset, foot_position, foot_jacobian,
                foot_angular_jacobian, radius, relative, velocity, rolling, motion_work)
    # --- prediction: the accelerometer, world frame
    accel = state[_ACCEL:_ACCEL + 3]
    world_accel[:] = 0.0
    if accel_ok:
        for k in range(3):
            accel[k] = accel_in[k]
        for r in range(3):
            world_accel[r] = (rotation[r, 0] * accel[0] + rotation[r, 1] * accel[1]
                              + rotation[r, 2] * accel[2])
        world_accel[2] -= _GRAVITY
    for a in range(3):
        xa = x[a]
        Pa = P[a]
        xa[0] += xa[1] * dt + 0.5 * world_accel[a] * dt * dt
        xa[1] += world_accel[a] * dt
        for c in range(6):  # F P
            Pa[0, c] += dt * Pa[1, c]
        for r in range(6):  # (F P) F^T
            Pa[r, 0] += dt * Pa[r, 1]
        Pa[0, 0] += sigma_p * sigma_p * dt
        Pa[1, 1] += sigma_v * sigma_v * dt
        for i in range(4):
            f = 2 + i
            if weight[i] >= min_weight:
                xa[f] += rolling[i, a] * dt
                Pa[f, f] += sigma_f * sigma_f * dt
            else:  # a free foot is where the kinematics put it
                xa[f] = xa[0] + relative[i, a]
                for c in range(6):
                    Pa[f, c] = Pa[0, c]
                for r in range(6):
                    Pa[r, f] = Pa[r, 0]
                Pa[f, f] = Pa[0, 0] + sigma_pos * sigma_pos
    # --- correction: each foot's kinematics, one scalar at a time
    if joints_ok:
        for i in range(4):
            if weight[i] < min_weight:
                continue
            scale = swing_scale ** (1.0 - min(1.0, weight[i]))
            f = 2 + i
            for a in range(3):
                _scalar_update(x[a], P[a], f, 0, relative[i, a], sigma_pos * sigma_pos * scale,
                               gain_vector, projected)
                _scalar_update(x[a], P[a], 1, -1, velocity[i, a],
                               sigma_vel * sigma_vel * scale, gain_vector, projected)
            _scalar_update(x[2], P[2], f, -1, radius, sigma_h * sigma_h * scale, gain_vector,
                           projected)
    write_outputs(rotation, quat, omega, x[0, 0], x[1, 0], x[2, 0], x[0, 1], x[1, 1], x[2, 1],
                  imu_offset, joint_q, joint_dq, q_out, v_out, output_work)
    account_trust(flags, dt, clock)
    return flags


@numba.njit(cache=True)
def write_outputs(rotation, quat, omega, px, py, pz, vx, vy, vz, imu_offset, joint_q, joint_dq,
                  q_out, v_out, work):  # pragma: no cover - compiled
    """The controller's ``(q, v)`` from the IMU site's world position ``(px, py, pz)`` and
    velocity ``(vx, vy, vz)``, the orientation (``rotation`` and ``quat`` as w, x, y, z), the
    body angular velocity and the joints (Pinocchio's conventions); ``work``: scratch (3, 3)."""
    offset, spin, base = work[0], work[1], work[2]
    for r in range(3):
        offset[r] = (rotation[r, 0] * imu_offset[0] + rotation[r, 1] * imu_offset[1]
                     + rotation[r, 2] * imu_offset[2])
        spin[r] = (rotation[r, 0] * omega[0] + rotation[r, 1] * omega[1]
                   + rotation[r, 2] * omega[2])
    # v_base = v_imu - omega_world x offset_world, then into the base frame.
    base[0] = vx - (spin[1] * offset[2] - spin[2] * offset[1])
    base[1] = vy - (spin[2] * offset[0] - spin[0] * offset[2])
    base[2] = vz - (spin[0] * offset[1] - spin[1] * offset[0])
    q_out[0] = px - offset[0]
    q_out[1] = py - offset[1]
    q_out[2] = pz - offset[2]
    for r in range(3):
        v_out[r] = rotation[0, r] * base[0] + rotation[1, r] * base[1] + rotation[2, r] * base[2]
        v_out[3 + r] = omega[r]
    q_out[3], q_out[4], q_out[5], q_out[6] = quat[1], quat[2], quat[3], quat[0]
    for j in range(12):
        q_out[7 + j] = joint_q[j]
        v_out[6 + j] = joint_dq[j]


@numba.njit(cache=True)
def _start(quat_in, q_in, params, imu_offset, rotations, translations, axes, foot_offsets,
           foot_position, foot_jacobian, foot_angular_jacobian, state, x, P, base_x, base_y,
           keep_yaw):  # pragma: no cover - compiled
    """Start on four loaded feet: orientation from the IMU (yaw 0 unless ``keep_yaw``),
    height from the feet on the floor, the base at ``(base_x, base_y)``, at rest."""
    sigma_pos, sigma_h, radius = params[7], params[9], params[12]
    measured = quat_in / math.sqrt(quat_in[0] ** 2 + quat_in[1] ** 2 + quat_in[2] ** 2
                                   + quat_in[3] ** 2)
    yaw = 0.0 if keep_yaw else quat_yaw(measured)
    align = state[_ALIGN:_ALIGN + 4]
    align[0], align[1], align[2], align[3] = math.cos(-0.5 * yaw), 0.0, 0.0, math.sin(-0.5 * yaw)
    quat = state[_QUAT:_QUAT + 4]
    quat_multiply(align, measured, quat)
    quat_normalize(quat)
    rotation = np.empty((3, 3))
    quat_rotation(quat, rotation)
    leg_kinematics(q_in, rotations, translations, axes, foot_offsets, foot_position,
                   foot_jacobian, foot_angular_jacobian, np.empty((4, 3, 3)))
    height = 0.0
    for i in range(4):
        height += radius - (rotation[2, 0] * foot_position[i, 0]
                            + rotation[2, 1] * foot_position[i, 1]
                            + rotation[2, 2] * foot_position[i, 2])
    base = np.array([base_x, base_y, height / 4.0])
    x[:, :] = 0.0
    P[:, :, :] = 0.0
    for a in range(3):
        x[a, 0] = base[a] + (rotation[a, 0] * imu_offset[0] + rotation[a, 1] * imu_offset[1]
                             + rotation[a, 2] * imu_offset[2])
        P[a, 0, 0] = (sigma_h * sigma_h) if a == 2 else 1e-8
        P[a, 1, 1] = 1e-4  # at rest, within 1 cm/s
        for i in range(4):
            f = 2 + i
            x[a, f] = base[a] + (rotation[a, 0] * foot_position[i, 0]
                                 + rotation[a, 1] * foot_position[i, 1]
                                 + rotation[a, 2] * foot_position[i, 2])
            P[a, f, 0] = P[a, 0, f] = P[a, 0, 0]
            P[a, f, f] = P[a, 0, 0] + sigma_pos * sigma_pos
            for k in range(i):
                P[a, f, 2 + k] = P[a, 2 + k, f] = P[a, 0, 0]
    state[_BIAS:_BIAS + 3] = 0.0
    state[_OMEGA:_OMEGA + 3] = 0.0
    state[_ACCEL:_ACCEL + 3] = 0.0
    state[_QUAT_AGE_S] = 0.0


def describe_faults(flags: int, record: SensorRecord, foot_reason: np.ndarray,
                    quaternion_tolerance: float, quaternion_timeout_s: float,
                    quaternion_note: str = "orientation from the gyroscope") -> str:
    """A tick's fault flags in words ('' when none), with the readings that raised them.

    Args:
        flags: The tick's fault flags.
        record: Its sample (description order).
        foot_reason: Why each foot sensor is distrusted (``FOOT_*``), ``LEGS`` order.
        quaternion_tolerance: The estimator's unit-norm tolerance.
        quaternion_timeout_s: Its time [s] on the gyroscope alone.
        quaternion_note: What the estimator does without the IMU's quaternion.
    """
    parts = []
    if flags & NO_DATA:
        parts.append("no sensor sample this period")
    if flags & STALE:
        parts.append(f"stale sample (tick {record.tick} repeated)")
    if flags & JOINTS_BAD:
        bad = [i for i in range(12)
               if not (math.isfinite(record.q[i]) and math.isfinite(record.dq[i]))]
        parts.append(f"joint readings non-finite at {bad}")
    if flags & GYRO_BAD:
        parts.append(f"gyroscope non-finite ({record.gyroscope_rad_s.tolist()})")
    if flags & ACCEL_BAD:
        parts.append(f"accelerometer non-finite ({record.accelerometer_m_s2.tolist()}): "
                     "predicting without it")
    if flags & QUATERNION_NON_FINITE:
        parts.append(f"IMU quaternion non-finite ({record.imu_quaternion_wxyz.tolist()}): "
                     f"{quaternion_note}")
    if flags & QUATERNION_NOT_UNIT:
        norm = float(np.linalg.norm(record.imu_quaternion_wxyz))
        parts.append(f"IMU quaternion not unit (norm {norm:.4g}, tolerance "
                     f"{quaternion_tolerance:g}): {quaternion_note}")
    if flags & QUATERNION_TIMEOUT:
        parts.append(f"no valid IMU quaternion for more than {quaternion_timeout_s:g} s")
    for i, leg in enumerate(LEGS):
        reason = int(foot_reason[i])
        if reason != FOOT_OK:
            value = record.foot_force[i]
            parts.append(f"{leg} foot-force sensor {_FOOT_REASONS[reason].format(value=value)}: "
                         "contact from the schedule")
    return "; ".join(parts)


# ----------------------------------------------------------------------------- the class


class StateEstimate:
    """What the estimator gives the controller, and what it thinks of it.

    Attributes:
        q: Configuration (19,), Pinocchio convention, description order (updated in place
            every tick: copy it to keep it).
        v: Velocity (18,): base linear and angular velocity in the base frame, joints.
        contact: Each foot's contact weight in ``LEGS`` order (4,): 1 a loaded stance foot,
            0 a foot the filter lets go.
        trusted: This tick's sample was fresh and complete (joints and gyroscope).
        untrusted_s: Time [s] since the last trustworthy sample.
        usable: ``untrusted_s`` is within the estimator's ``trust_timeout_s``.
        flags: The tick's fault flags (the module's constants).
        faults: What the estimator distrusts, in words ('' when nothing).
    """

    def __init__(self) -> None:
        self.q = np.zeros(19)
        self.q[6] = 1.0
        self.v = np.zeros(18)
        self.contact = np.ones(len(LEGS))
        self.trusted = True
        self.untrusted_s = 0.0
        self.usable = True
        self.flags = 0
        self.faults = ""


class EstimatorBase:
    """What the estimators share: their inputs, the foot sensors' state, the clock, the
    bound compiled tick, :meth:`reset` and :meth:`update`.

    A subclass names its config class (``config_class``) and compiled tick (``kernel``),
    and gives :meth:`_filter_arrays` (its filter's arrays, passed to the kernel between the
    clock and the foot sensors' state) and :meth:`_start_filter`.

    Args:
        config: Every number (the config class's defaults when ``None``).
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of the config to change.
    """

    config_class: ClassVar[type[SensorTrustConfig]] = SensorTrustConfig
    kernel: ClassVar[Any] = None
    #: What the estimator does without the IMU's quaternion (the fault text says it).
    quaternion_note: ClassVar[str] = "orientation from the gyroscope"
    #: The kernel's scratch space [floats].
    work_size: ClassVar[int] = 0

    def __init__(self, config: SensorTrustConfig | None = None, *,
                 description: Go2Description | None = None, control_period_s: float = 1e-3,
                 **overrides: Any):
        base = config or self.config_class()
        unknown = sorted(set(overrides) - set(self.config_class.field_names()))
        if unknown:
            raise ConfigurationError(
                f"unknown estimator parameter(s) {unknown}; valid parameters: "
                f"{', '.join(self.config_class.field_names())}")
        self.config = replace(base, **overrides)
        self.control_period_s = as_float("control_period_s", control_period_s, low=0.0,
                                         high=0.1, low_inclusive=False)
        self.legs = LegKinematics(description)
        self.estimate = StateEstimate()
        self._params = self.config._vector()
        #: Last sample's tick and stamp [s], time without a trusted one [s], time predicted
        #: since the last sample [s].
        self._clock = np.array([-1.0, 0.0, 0.0, 0.0])
        self._foot_contact = np.ones(4)
        self._foot_same_s = np.zeros(4)
        self._foot_good_s = np.zeros(4)
        self._foot_reason = np.zeros(4, dtype=np.int64)
        self._foot_last = np.full(4, np.nan)
        self._joint_q = np.zeros(12)
        self._joint_dq = np.zeros(12)
        self._work = np.zeros(self.work_size)
        #: The last sample that came (the fault text quotes its readings).
        self._input = SensorRecord.zeros()
        self._schedule = np.zeros(4)
        self._fresh = False  # the last tick had a sample
        self._described = 0  # the flags the estimate's ``faults`` text describes
        self._tick: Any = None
        self.started = False

    def _filter_arrays(self) -> tuple[np.ndarray, ...]:
        raise NotImplementedError

    def _start_filter(self, quaternion: np.ndarray, joint_q: np.ndarray,
                      base_xy: tuple[float, float], keep_yaw: bool) -> None:
        raise NotImplementedError

    # -- start ---------------------------------------------------------------------------

    def reset(self, record: SensorRecord, *, base_xy: tuple[float, float] = (0.0, 0.0),
              keep_yaw: bool = False) -> StateEstimate:
        """Start from ``record`` on four loaded feet, at rest (description order).

        Args:
            record: The first sample: its quaternion and joint angles must be finite and
                the quaternion a unit one.
            base_xy: Where the base is in the estimator's world [m] (the origin by default).
            keep_yaw: Keep the IMU's yaw; by default the estimator's world has the base's
                heading at zero.

        Raises:
            ConfigurationError: A record that cannot start the estimator (the field named);
                nothing is changed.
        """
        if not isinstance(record, SensorRecord):
            raise ConfigurationError(
                f"record: expected a SensorRecord, received {type(record).__name__}")
        quat = as_vector("imu_quaternion_wxyz", record.imu_quaternion_wxyz, 4)
        norm = float(np.linalg.norm(quat))
        if abs(norm - 1.0) > self.config.quaternion_tolerance:
            raise ConfigurationError(
                f"imu_quaternion_wxyz: expected a unit quaternion (w, x, y, z) to start from, "
                f"received {quat.tolist()} (norm {norm:g})")
        joint_q = as_vector("q", record.q, 12)
        as_vector("dq", record.dq, 12)
        self._start_filter(quat, joint_q, (float(base_xy[0]), float(base_xy[1])),
                           bool(keep_yaw))
        self._foot_contact[:] = 1.0
        self._foot_same_s[:] = 0.0
        self._foot_good_s[:] = 0.0
        self._foot_reason[:] = FOOT_OK
        self._foot_last[:] = np.nan
        # The record itself is the first sample.
        self._clock[:] = (record.tick - 1, record.stamp_s - self.control_period_s, 0.0, 0.0)
        self._described = 0
        self.estimate.faults = ""
        self.started = True
        self._schedule[:] = np.inf  # four loaded feet
        return self.update(record, self._schedule)

    # -- the tick ------------------------------------------------------------------------

    def update(self, record: SensorRecord | None, normal_force_bounds: np.ndarray
               ) -> StateEstimate:
        """One tick: ``record`` (``None`` when no sample arrived) and the contact schedule.

        Args:
            record: This period's sample, description order; ``None`` when none came.
            normal_force_bounds: Each foot's normal-force bound [N] in the controller, in
                ``LEGS`` order (0 for a foot in swing): the contact schedule. A controller
                fills it with ``normal_force_bounds(out)``.

        Returns:
            The estimate (the same object every tick, updated in place).

        Raises:
            ConfigurationError: Not started (call :meth:`reset` first), or a schedule of the
                wrong shape.
        """
        if not self.started:
            raise ConfigurationError(
                f"{type(self).__name__}.update: call reset(record) first")
        if normal_force_bounds is not self._schedule:
            schedule = self._schedule
            try:
                schedule[:] = normal_force_bounds
            except (ValueError, TypeError):
                raise ConfigurationError(
                    f"normal_force_bounds: expected 4 numbers (FL, FR, RL, RR) [N], received "
                    f"{normal_force_bounds!r}") from None
        if record is None:  # the kernel reads nothing of a sample that did not come
            fresh, record = False, self._input
        else:
            fresh, self._input = True, record
        self._fresh = fresh
        if self._tick is None:
            self._tick = self._bind()
        try:
            flags = int(self._tick(fresh, record))
        except (TypeError, AttributeError):
            if isinstance(record, SensorRecord):  # its arrays were replaced after construction
                record = SensorRecord(**{f.name: getattr(record, f.name)
                                         for f in fields(SensorRecord)})
            else:
                raise ConfigurationError(
                    f"record: expected a SensorRecord or None, received "
                    f"{type(record).__name__}") from None
            self._input = record
            flags = int(self._tick(fresh, record))
        estimate = self.estimate
        estimate.flags = flags
        estimate.trusted = not flags & UNTRUSTED
        estimate.untrusted_s = float(self._clock[_UNTRUSTED_S])
        # (A tolerance for the sum of periods: ten 1 ms ticks are 10 ms, not 10.000000000002.)
        estimate.usable = estimate.untrusted_s <= self.config.trust_timeout_s + 1e-9
        if flags != self._described:  # the text is built when what it says changes
            self._described = flags
            estimate.faults = self.describe(flags)
        return estimate

    def _bind(self) -> Any:
        """The kernel's compiled overload with the estimator's own arrays bound; the
        sample's are passed per call (read where they are: no copy)."""
        legs, estimate = self.legs, self.estimate
        arrays = (
            self._schedule, self.control_period_s, self._params, legs.imu_offset,
            legs.rotations, legs.translations, legs.axes, legs.foot_offsets,
            legs.foot_position, legs.foot_jacobian, legs.foot_angular_jacobian, self._clock,
            *self._filter_arrays(), self._foot_contact, self._foot_same_s, self._foot_good_s,
            self._foot_reason, self._foot_last, self._joint_q, self._joint_dq, estimate.q,
            estimate.v, estimate.contact, self._work)
        sample = self._input
        compiled = bind_compiled(
            self.kernel, True, 0.0, 0.0, sample.imu_quaternion_wxyz, sample.gyroscope_rad_s,
            sample.accelerometer_m_s2, sample.q, sample.dq, sample.foot_force, *arrays).func
        self._tick_arrays = arrays

        def tick(fresh: bool, record: SensorRecord) -> int:
            return compiled(fresh, float(record.tick), record.stamp_s,
                            record.imu_quaternion_wxyz, record.gyroscope_rad_s,
                            record.accelerometer_m_s2, record.q, record.dq, record.foot_force,
                            *arrays)

        return tick

    # -- reporting -----------------------------------------------------------------------

    @property
    def last_sample(self) -> SensorRecord | None:
        """The last tick's sample (``None`` if none came; the caller's record, not a copy)."""
        return self._input if self._fresh else None

    @property
    def last_schedule(self) -> np.ndarray:
        """The contact schedule [N] the last tick was given (a copy)."""
        return self._schedule.copy()

    def describe(self, flags: int | None = None) -> str:
        """What the estimator distrusts this tick, in words ('' when nothing), with the
        readings of the last sample that arrived."""
        return describe_faults(self.estimate.flags if flags is None else flags, self._input,
                               self._foot_reason, self.config.quaternion_tolerance,
                               self.config.quaternion_timeout_s, self.quaternion_note)


class StateEstimator(EstimatorBase):
    """The base's state from a GO2's sensors (see the module docstring).

    Args:
        config: Every number (defaults when ``None``); see :class:`EstimatorConfig`.
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of :class:`EstimatorConfig` to change.

    Example:
        >>> estimator = StateEstimator(control_period_s=2e-3)
        >>> estimator.reset(record)                       # four feet on the floor
        >>> loads = np.zeros(4)
        >>> controller.normal_force_bounds(loads)         # the contact schedule
        >>> estimate = estimator.update(record, loads)    # every tick
        >>> out = controller.step(estimate.q, estimate.v)
    """

    config_class = EstimatorConfig
    kernel = _estimate
    work_size = _WORK_SIZE
    config: EstimatorConfig

    def __init__(self, config: EstimatorConfig | None = None, *,
                 description: Go2Description | None = None, control_period_s: float = 1e-3,
                 **overrides: Any):
        super().__init__(config, description=description, control_period_s=control_period_s,
                         **overrides)
        self._state = np.zeros(_STATE_SIZE)
        self._state[_QUAT] = 1.0
        self._state[_ALIGN] = 1.0
        self._x = np.zeros((3, 6))
        self._P = np.zeros((3, 6, 6))

    def _filter_arrays(self) -> tuple[np.ndarray, ...]:
        return self._state, self._x, self._P

    def _start_filter(self, quaternion: np.ndarray, joint_q: np.ndarray,
                      base_xy: tuple[float, float], keep_yaw: bool) -> None:
        legs = self.legs
        _start(quaternion, joint_q, self._params, legs.imu_offset, legs.rotations,
               legs.translations, legs.axes, legs.foot_offsets, legs.foot_position,
               legs.foot_jacobian, legs.foot_angular_jacobian, self._state, self._x, self._P,
               base_xy[0], base_xy[1], keep_yaw)

    @property
    def gyro_bias(self) -> np.ndarray:
        """The learnt gyroscope bias [rad/s] (a copy)."""
        return self._state[_BIAS:_BIAS + 3].copy()

    @property
    def foot_positions(self) -> np.ndarray:
        """The filter's foot centres (4, 3) [m], estimator world frame (a copy)."""
        return self._x[:, 2:].T.copy()
