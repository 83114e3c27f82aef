"""The compiled pieces every estimator's tick shares: the sample's checks, the trust clock, the
feet's contact weights and motion, the starting pose and the controller's ``(q, v)``.

So both estimators read a sample, weigh a foot and report a fault the same way, and differ
only in their filters (:mod:`wbc.estimation.state_estimator_kernels`,
:mod:`wbc.estimation.invariant_ekf_kernels`). Nothing here allocates.
"""

from __future__ import annotations

import math

import numba

from wbc.core.quaternion_kernels import quat_multiply, quat_normalize, quat_rotation, quat_yaw
from wbc.estimation.kernel_groups import (
    CLOCK_PREDICTED_S,
    CLOCK_STAMP_S,
    CLOCK_TICK,
    CLOCK_UNTRUSTED_S,
    HEADER_FRESH,
    HEADER_STAMP_S,
    HEADER_TICK,
    Sample,
)
from wbc.estimation.state_estimate import (
    ACCEL_BAD,
    FOOT_NON_FINITE,
    FOOT_OK,
    FOOT_REASON_SHIFT,
    FOOT_SATURATED,
    FOOT_SENSOR,
    FOOT_STUCK,
    FOOT_WEIGHT,
    GYRO_BAD,
    JOINTS_BAD,
    NO_DATA,
    QUATERNION_NON_FINITE,
    QUATERNION_NOT_UNIT,
    STALE,
    UNTRUSTED,
)
from wbc.model.leg_kinematics import leg_kinematics

#: The foot sensors' calibration and weight check, one array (``foot_cal``): each foot's
#: offset [counts] and gain [counts/N] (``LEGS`` order), the robot's weight [N], the time the
#: evidence has contradicted it [s], the time it has agreed since [s], the fault (1: raised)
#: and the last sum of the calibrated forces [N].
CAL_OFFSET, CAL_GAIN, CAL_WEIGHT = 0, 4, 8
CAL_BAD_S, CAL_GOOD_S, CAL_ACTIVE, CAL_SUM = 9, 10, 11, 12
CAL_SIZE = 13


@numba.njit(cache=True)
def sample_of(header, readings):  # pragma: no cover - compiled
    """The :class:`~wbc.estimation.kernel_groups.Sample` of a header (``HEADER_*``: fresh
    as 1 or 0, tick, stamp [s]) and its :class:`~wbc.estimation.kernel_groups.Readings`."""
    return Sample(header[HEADER_FRESH] != 0.0, header[HEADER_TICK], header[HEADER_STAMP_S],
                  readings.quaternion, readings.gyroscope, readings.accelerometer, readings.q,
                  readings.dq, readings.foot_force)


@numba.njit(cache=True)
def check_sample(sample, clock, dt_nominal, quat_tol):  # pragma: no cover - compiled
    """Which parts of this tick's sample can be used; the time step.

    Args:
        sample: This tick's :class:`~wbc.estimation.kernel_groups.Sample`.
        clock: In/out: :attr:`SensorState.clock` (the ``CLOCK_*`` entries).
        dt_nominal: The control period [s], used when the stamps do not give the step.
        quat_tol: Largest ``| |quat| - 1 |`` of a usable quaternion.

    Returns:
        ``(flags, dt, new, quat_ok, gyro_ok, accel_ok, joints_ok)``: the fault flags so far,
        the time step [s], a new sample (not repeated), and each part's usability.
    """
    flags = 0
    dt = dt_nominal
    new = sample.fresh
    if not sample.fresh:
        flags |= NO_DATA
    elif sample.tick == clock[CLOCK_TICK]:
        flags |= STALE
        new = False
    if new:
        # The step from the last sample, less what was predicted since without one.
        elapsed = sample.stamp_s - clock[CLOCK_STAMP_S]
        if 0.0 < elapsed < 0.1:
            dt = max(0.0, elapsed - clock[CLOCK_PREDICTED_S])
        clock[CLOCK_TICK] = sample.tick
        clock[CLOCK_STAMP_S] = sample.stamp_s
        clock[CLOCK_PREDICTED_S] = 0.0
    else:
        clock[CLOCK_PREDICTED_S] += dt
    q_in, dq_in = sample.q, sample.dq
    gyro_in, accel_in, quat_in = sample.gyroscope, sample.accelerometer, sample.quaternion
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
    """Add ``dt`` [s] to the untrusted time of ``clock`` if the tick's flags make it
    untrustworthy, else reset it."""
    if flags & UNTRUSTED:
        clock[CLOCK_UNTRUSTED_S] += dt
    else:
        clock[CLOCK_UNTRUSTED_S] = 0.0


@numba.njit(cache=True)
def contact_weights(new, dt, force_in, schedule, params, sensors,
                    weight):  # pragma: no cover - compiled
    """Each foot's contact weight: the schedule, fused with its foot-force sensor.

    The schedule's weight is the foot's normal-force bound over ``full_trust_force_n``
    (clipped to [0, 1]); the sensor's verdict is a hysteresis between ``foot_force_off_n``
    and ``foot_force_on_n`` [N], its count turned into newtons by the calibration in
    ``foot_cal``. A sensor at full scale (``foot_force_full_scale`` counts), non-finite, or
    (on a scheduled stance foot) repeating one reading for ``foot_sensor_stuck_s`` [s] is
    distrusted until it has read changing, in-range values for ``foot_sensor_recover_s``
    [s]; the schedule alone then decides for that foot. Without foot sensors
    (``use_foot_force`` false) their readings are not judged: the schedule decides every
    foot.

    The weight check: while at least three feet are scheduled to stand and every sensor is
    trusted, the calibrated forces must sum to between ``weight_low_fraction`` and
    ``weight_high_fraction`` times the robot's weight; evidence outside for
    ``weight_check_s`` [s] raises :data:`FOOT_WEIGHT`, and the schedule alone decides every
    foot until the sum has been back inside for ``foot_sensor_recover_s``.

    Args:
        new, dt: A new sample came; the time step [s].
        force_in: The sample's foot-force counts (4,).
        schedule: Each foot's normal-force bound [N] (4,).
        params: The estimator's parameter record (the fields above, by name).
        sensors: In/out: :class:`~wbc.estimation.kernel_groups.SensorState` (``foot_cal``
            laid out as :data:`CAL_SIZE` says).
        weight: Out (4,): each foot's contact weight.

    Returns:
        :data:`FOOT_SENSOR` if a foot sensor is distrusted, else 0, with each foot's reason
        in two bits from :data:`FOOT_REASON_SHIFT`, and :data:`FOOT_WEIGHT`.
    """
    full_force, use_force = params.full_trust_force_n, params.use_foot_force
    force_on, force_off = params.foot_force_on_n, params.foot_force_off_n
    force_full, stuck_s = params.foot_force_full_scale, params.foot_sensor_stuck_s
    recover_s, weight_check_s = params.foot_sensor_recover_s, params.weight_check_s
    weight_low, weight_high = params.weight_low_fraction, params.weight_high_fraction
    foot_contact, foot_same_s, foot_good_s = (sensors.foot_contact, sensors.foot_same_s,
                                              sensors.foot_good_s)
    foot_reason, foot_last, foot_cal = sensors.foot_reason, sensors.foot_last, sensors.foot_cal
    flags = 0
    total = 0.0
    standing = 0
    all_ok = True
    for i in range(4):
        scheduled = min(1.0, max(0.0, schedule[i] / full_force))
        if scheduled >= 1.0:
            standing += 1
        if new and use_force:  # without foot sensors their readings mean nothing
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
                newtons = (value - foot_cal[CAL_OFFSET + i]) / foot_cal[CAL_GAIN + i]
                total += newtons
                if newtons > force_on:
                    foot_contact[i] = 1.0
                elif newtons < force_off:
                    foot_contact[i] = 0.0
        if use_force and foot_reason[i] != FOOT_OK:
            flags |= FOOT_SENSOR | (foot_reason[i] << (FOOT_REASON_SHIFT + 2 * i))
            all_ok = False
    if new and use_force and all_ok and standing >= 3:
        foot_cal[CAL_SUM] = total
        robot = foot_cal[CAL_WEIGHT]
        if total < weight_low * robot or total > weight_high * robot:
            foot_cal[CAL_BAD_S] += dt
            foot_cal[CAL_GOOD_S] = 0.0
            if foot_cal[CAL_BAD_S] >= weight_check_s:
                foot_cal[CAL_ACTIVE] = 1.0
        else:
            foot_cal[CAL_BAD_S] = 0.0
            if foot_cal[CAL_ACTIVE] > 0.0:
                foot_cal[CAL_GOOD_S] += dt
                if foot_cal[CAL_GOOD_S] >= recover_s:
                    foot_cal[CAL_ACTIVE] = 0.0
    contradicted = use_force and foot_cal[CAL_ACTIVE] > 0.0
    if contradicted:
        flags |= FOOT_WEIGHT
    for i in range(4):
        scheduled = min(1.0, max(0.0, schedule[i] / full_force))
        if use_force and not contradicted and foot_reason[i] == FOOT_OK:
            weight[i] = scheduled * foot_contact[i]
        else:
            weight[i] = scheduled
    return flags


@numba.njit(cache=True)
def legs_and_contacts(joints_ok, new, dt, sample, schedule, params, legs, sensors, outputs,
                      legs_work):  # pragma: no cover - compiled
    """The joints (kept in ``outputs`` when usable), the legs' kinematics (``legs``,
    scratch ``legs_work`` (4, 3, 3)) and each foot's contact weight
    (:func:`contact_weights`, into ``outputs.contact``); the contact flags.

    ``params`` is the estimator's parameter record: every estimator's has the contact
    fusion's fields (:data:`wbc.estimation.estimator_config.CONTACT_PARAMS`).
    """
    joint_q, joint_dq = outputs.joint_q, outputs.joint_dq
    if joints_ok:
        for j in range(12):
            joint_q[j] = sample.q[j]
            joint_dq[j] = sample.dq[j]
        # (``legs_work[:]``: a plain array view, as leg_kinematics' signature takes.)
        leg_kinematics(joint_q, legs.rotations, legs.translations, legs.axes,
                       legs.foot_offsets, legs.foot_position, legs.foot_jacobian,
                       legs.foot_angular_jacobian, legs_work[:])
    return contact_weights(new, dt, sample.foot_force, schedule, params, sensors,
                           outputs.contact)


@numba.njit(cache=True)
def foot_motion(rotation, omega, joint_dq, origin, legs, radius, relative, velocity, rolling,
                work):  # pragma: no cover - compiled
    """Each foot's kinematics in the world's orientation, relative to a point of the base.

    Args:
        rotation: The base's orientation ``R_world_base`` (3, 3).
        omega: The base's angular velocity, base frame [rad/s].
        joint_dq: Joint velocities [rad/s] (12,), description order.
        origin: The point of the base [m] (the IMU), base frame.
        legs: :class:`~wbc.estimation.kernel_groups.Legs` (its outputs are read).
        radius: The foot spheres' radius [m].
        relative: Out (4, 3): each foot centre minus the point, world orientation [m].
        velocity: Out (4, 3): the point's world velocity [m/s] if the foot's sphere rolls
            on the floor without slipping.
        rolling: Out (4, 3): the foot centre's world velocity as its sphere rolls
            (``omega_foot x (0, 0, radius)``) [m/s].
        work: The work record (its ``foot_*`` arrays are scratch).
    """
    body, spin = work.foot_body, work.foot_spin
    rel_v, world_spin = work.foot_relative_velocity, work.foot_world_spin
    foot_position, foot_jacobian = legs.foot_position, legs.foot_jacobian
    foot_angular_jacobian = legs.foot_angular_jacobian
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
def write_outputs(rotation, quat, omega, px, py, pz, vx, vy, vz, imu_offset, outputs,
                  work):  # pragma: no cover - compiled
    """The controller's ``(q, v)`` (into ``outputs``) from the IMU site's world position
    ``(px, py, pz)`` and velocity ``(vx, vy, vz)``, the orientation (``rotation`` and
    ``quat`` as w, x, y, z), the body angular velocity and ``outputs``' joints (Pinocchio's
    conventions); ``work``: the work record (its ``output_*`` arrays are scratch)."""
    offset, spin, base = work.output_offset, work.output_spin, work.output_base
    joint_q, joint_dq, q_out, v_out = outputs.joint_q, outputs.joint_dq, outputs.q, outputs.v
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
def start_pose(quat_in, q_in, keep_yaw, base_x, base_y, radius, legs, align, quat,
               imu_position, feet, work):  # pragma: no cover - compiled
    """Where an estimator starts: on four loaded feet, the base at ``(base_x, base_y)`` [m].

    The orientation is the IMU's quaternion ``quat_in`` (w, x, y, z; normalised here) turned
    to yaw 0 unless ``keep_yaw``; the height puts the feet's sphere centres (``radius`` [m])
    on a flat floor at z = 0, on average.

    Args:
        quat_in, q_in: The first sample's quaternion and joint angles [rad] (12,).
        legs: :class:`~wbc.estimation.kernel_groups.Legs` (its outputs are filled for
            ``q_in``).
        align: Out (4,): the yaw alignment, ``quat = align * quat_in / |quat_in|``.
        quat: Out (4,): the orientation (w, x, y, z).
        imu_position: Out (3,): the IMU site's world position [m].
        feet: Out (4, 3): the foot centres' world positions [m].
        work: The work record (its ``start_*`` arrays and ``legs`` are scratch).
    """
    measured, rotation = work.start_measured, work.start_rotation
    legs_work = work.legs[:]  # a plain array view, as leg_kinematics' signature takes
    imu_offset, foot_position = legs.imu_offset, legs.foot_position
    norm = math.sqrt(quat_in[0] ** 2 + quat_in[1] ** 2 + quat_in[2] ** 2 + quat_in[3] ** 2)
    for k in range(4):
        measured[k] = quat_in[k] / norm
    yaw = 0.0 if keep_yaw else quat_yaw(measured)
    align[0], align[1], align[2], align[3] = math.cos(-0.5 * yaw), 0.0, 0.0, math.sin(-0.5 * yaw)
    quat_multiply(align, measured, quat)
    quat_normalize(quat)
    quat_rotation(quat, rotation)
    leg_kinematics(q_in, legs.rotations, legs.translations, legs.axes, legs.foot_offsets,
                   foot_position, legs.foot_jacobian, legs.foot_angular_jacobian, legs_work)
    height = 0.0
    for i in range(4):
        height += radius - (rotation[2, 0] * foot_position[i, 0]
                            + rotation[2, 1] * foot_position[i, 1]
                            + rotation[2, 2] * foot_position[i, 2])
    height /= 4.0
    for r in range(3):
        base = base_x if r == 0 else (base_y if r == 1 else height)
        imu_position[r] = base + (rotation[r, 0] * imu_offset[0]
                                  + rotation[r, 1] * imu_offset[1]
                                  + rotation[r, 2] * imu_offset[2])
        for i in range(4):
            feet[i, r] = base + (rotation[r, 0] * foot_position[i, 0]
                                 + rotation[r, 1] * foot_position[i, 1]
                                 + rotation[r, 2] * foot_position[i, 2])
