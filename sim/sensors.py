"""What the simulated GO2 measures: IMU, joint encoders and torques, foot-force counts, with noise.

MuJoCo's sensor ``noise`` attribute is stored, never applied; this module adds the noise
itself, seeded, once per control period. A :class:`sim.sensor_model.SensorModel` names the
numbers (presets in :data:`SENSOR_PRESETS`, any field changed by name; both are importable
from here too); :class:`SimulatedSensors` turns the plant's true state into a
:class:`wbc.SensorRecord` in the plant's joint and leg order, as a real GO2's
``rt/lowstate`` would deliver it. The true state stays on the simulator for
metrics, logs and tests; the controller only ever sees the records.

How each signal is made, every control period of ``dt`` seconds:

- gyroscope: the base's angular velocity (base frame) + bias + white noise; the bias starts
  at a random draw and walks (``gyro_bias_walk`` [rad/s/sqrt(s)]).
- accelerometer: the specific force at the IMU site (the URDF's ``imu`` frame), from the
  site's velocity change over the period (what an IMU's anti-aliasing filter delivers) minus
  gravity, in the IMU frame; + bias (random start, random walk) + white noise.
- orientation: the robot's own attitude filter, a complementary filter on the noisy gyro and
  accelerometer that pulls roll and pitch towards the accelerometer's gravity with time
  constant ``attitude_time_constant_s``; it has no magnetometer, so its yaw drifts with the
  gyro's z bias. Its integral term (critically damped) learns the roll and pitch gyro
  bias. It starts where it settles at rest, tilted by the accelerometer's bias over g (a
  real one has run since power-up). A time constant of 0 reports the truth.
- joints: position + white noise, then quantised to the encoder's resolution; velocity +
  white noise; torque (the drivers' applied torque) + white noise. Robot joint order.
- feet: a raw count ``offset + gain * normal force + noise``, clipped to ``[0, full scale]``
  and rounded when ``foot_force_integer`` (the message's int16). Robot leg order.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numba
import numpy as np

from sim.sensor_groups import PlantReading, RecordArrays, SensorDrift, SensorSites
from sim.sensor_model import DEFAULT_SENSORS, SENSOR_PRESETS, SensorModel
from wbc.core.compiled_program import CompiledProgram
from wbc.core.errors import ConfigurationError
from wbc.core.kernel_records import parameter_record
from wbc.core.quaternion_kernels import quat_exp, quat_multiply, quat_normalize, rotate_inverse
from wbc.core.validation import check_name
from wbc.model.description import LEGS
from wbc.robot_io.sensor_record import SensorRecord

if TYPE_CHECKING:
    from sim.simulator import Go2Simulator

#: Samples' worth of standard normal draws generated at a time, refilled in place when used
#: up: ~25 us every 16 samples, where 1024 at once stalled the sample that refilled by ~0.4 ms.
#: The draws come in the same order whatever the block (NumPy fills row by row from one
#: stream), so the block size changes no value.
_NOISE_BLOCK = 16
#: Noise channels a sample draws: gyro (3), gyro bias walk (3), accel (3), accel bias walk
#: (3), joint position, velocity and torque (12 each), feet (4).
_CHANNELS = 52
_GRAVITY = 9.81


# ------------------------------------------------------------------------- the sampler

#: The sensor model's fields the compiled sampler reads (by name, from a parameter record).
_PARAMS = ("gyro_noise_rad_s", "gyro_bias_walk", "accel_noise_m_s2", "accel_bias_walk",
           "attitude_time_constant_s", "joint_position_noise_rad",
           "joint_position_resolution_rad", "joint_velocity_noise_rad_s",
           "joint_torque_noise_nm", "foot_force_offset", "foot_force_gain", "foot_force_noise",
           "foot_force_full_scale", "foot_force_integer")


def sampler_params(model: SensorModel) -> np.ndarray:
    """The parameter record of ``model`` the compiled sampler reads (:data:`_PARAMS`)."""
    return parameter_record({name: bool(getattr(model, name)) if name == "foot_force_integer"
                             else float(getattr(model, name)) for name in _PARAMS})


@numba.njit(cache=True)
def _sample(plant, sites, params, drift, noise, out):  # pragma: no cover - compiled
    """One sensor sample from MuJoCo's state (see the module docstring).

    Args:
        plant: :class:`PlantReading`.
        sites: :class:`SensorSites`.
        params: The parameter record (:func:`sampler_params`).
        drift: In/out :class:`SensorDrift`.
        noise: Standard normal draws (52,).
        out: Out :class:`RecordArrays`.
    """
    p = params[0]
    gyro_noise, gyro_walk = p.gyro_noise_rad_s, p.gyro_bias_walk
    accel_noise, accel_walk = p.accel_noise_m_s2, p.accel_bias_walk
    tau_attitude = p.attitude_time_constant_s
    q_noise, q_step = p.joint_position_noise_rad, p.joint_position_resolution_rad
    dq_noise, tau_noise = p.joint_velocity_noise_rad_s, p.joint_torque_noise_nm
    ff_offset, ff_gain, ff_noise = p.foot_force_offset, p.foot_force_gain, p.foot_force_noise
    ff_full, ff_integer = p.foot_force_full_scale, p.foot_force_integer
    qpos, qvel, dt = plant.qpos, plant.qvel, plant.dt
    imu_offset, site_velocity = sites.imu_offset, drift.site_velocity
    gyro_bias, accel_bias = drift.gyro_bias, drift.accel_bias
    attitude, integral = drift.attitude, drift.integral
    quaternion, gyroscope, accelerometer = out.quaternion, out.gyroscope, out.accelerometer
    true_quat = qpos[3:7]
    omega = qvel[3:6]
    # IMU site's world velocity: v_base + R (omega x r).
    cx = omega[1] * imu_offset[2] - omega[2] * imu_offset[1]
    cy = omega[2] * imu_offset[0] - omega[0] * imu_offset[2]
    cz = omega[0] * imu_offset[1] - omega[1] * imu_offset[0]
    w, x, y, z = true_quat[0], true_quat[1], true_quat[2], true_quat[3]
    r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    r10, r11, r12 = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    r20, r21, r22 = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
    vx = qvel[0] + r00 * cx + r01 * cy + r02 * cz
    vy = qvel[1] + r10 * cx + r11 * cy + r12 * cz
    vz = qvel[2] + r20 * cx + r21 * cy + r22 * cz
    force = np.empty(3)
    if plant.has_previous and dt > 0.0:
        force[0] = (vx - site_velocity[0]) / dt
        force[1] = (vy - site_velocity[1]) / dt
        force[2] = (vz - site_velocity[2]) / dt + _GRAVITY
    else:
        force[0] = 0.0
        force[1] = 0.0
        force[2] = _GRAVITY
    site_velocity[0], site_velocity[1], site_velocity[2] = vx, vy, vz
    rotate_inverse(true_quat, force, accelerometer)
    root = math.sqrt(dt)
    for k in range(3):
        gyro_bias[k] += gyro_walk * root * noise[3 + k]
        accel_bias[k] += accel_walk * root * noise[9 + k]
        gyroscope[k] = omega[k] + gyro_bias[k] + gyro_noise * noise[k]
        accelerometer[k] += accel_bias[k] + accel_noise * noise[6 + k]
    if tau_attitude <= 0.0:
        for k in range(4):
            quaternion[k] = true_quat[k]
            attitude[k] = true_quat[k]
    else:
        # Complementary filter: integrate the gyro, then turn the filter's "up" towards
        # the accelerometer's by dt / tau (roll and pitch only: gravity says nothing of yaw).
        up = np.empty(3)
        world_up = np.array([0.0, 0.0, 1.0])
        rotate_inverse(attitude, world_up, up)
        norm = math.sqrt(accelerometer[0] ** 2 + accelerometer[1] ** 2 + accelerometer[2] ** 2)
        gain = dt / tau_attitude
        ex = ey = ez = 0.0
        if norm > 1e-6:
            ax, ay, az = accelerometer[0] / norm, accelerometer[1] / norm, accelerometer[2] / norm
            # Measured "up" x estimated "up": the body-frame rotation that turns the
            # estimate towards the measurement.
            ex = ay * up[2] - az * up[1]
            ey = az * up[0] - ax * up[2]
            ez = ax * up[1] - ay * up[0]
        # Its integral term learns the gyro's roll and pitch bias (critically damped:
        # ki = kp^2 / 4), so that a constant bias leaves no lasting tilt error.
        ki_dt = 0.25 * dt / (tau_attitude * tau_attitude)
        integral[0] += ki_dt * ex
        integral[1] += ki_dt * ey
        integral[2] += ki_dt * ez
        step = np.empty(4)
        quat_exp((gyroscope[0] + integral[0]) * dt + gain * ex,
                 (gyroscope[1] + integral[1]) * dt + gain * ey,
                 (gyroscope[2] + integral[2]) * dt + gain * ez, step)
        quat_multiply(attitude, step, quaternion)
        quat_normalize(quaternion)
        for k in range(4):
            attitude[k] = quaternion[k]
    q, dq, tau, feet = out.q, out.dq, out.tau, out.feet
    joint_qpos, joint_dof, leg_rows = sites.joint_qpos, sites.joint_dof, sites.leg_rows
    actuator_force, touch = plant.actuator_force, plant.touch
    for j in range(q.shape[0]):
        angle = qpos[joint_qpos[j]] + q_noise * noise[12 + j]
        if q_step > 0.0:
            angle = q_step * math.floor(angle / q_step + 0.5)
        q[j] = angle
        dq[j] = qvel[joint_dof[j]] + dq_noise * noise[24 + j]
        tau[j] = actuator_force[j] + tau_noise * noise[36 + j]
    for i in range(feet.shape[0]):
        count = ff_offset + ff_gain * touch[leg_rows[i]] + ff_noise * noise[48 + i]
        count = min(max(count, 0.0), ff_full)
        if ff_integer:
            count = math.floor(count + 0.5)
        feet[i] = count


#: The per-sample numbers :func:`_sample_from_header` reads from its header: the time since
#: the previous sample [s], whether there was one (1 or 0), the noise block's row.
_DT, _HAS_PREVIOUS, _ROW = 0, 1, 2


@numba.njit(cache=True)
def _sample_from_header(header, plant, sites, params, drift, noise_block,
                        out):  # pragma: no cover - compiled
    """:func:`_sample`, ``dt``, ``has_previous`` and the noise row read from ``header`` (not
    ``plant``'s): the form of the one call whose arrays come from a table of addresses."""
    reading = PlantReading(plant.qpos, plant.qvel, plant.actuator_force, plant.touch,
                           header[_DT], header[_HAS_PREVIOUS] != 0.0)
    _sample(reading, sites, params, drift, noise_block[int(header[_ROW])], out)


class SimulatedSensors:
    """Samples the plant's sensors into a :class:`wbc.SensorRecord`, seeded.

    The record is in the plant's actuator (joint) order and in ``leg_order`` for the feet,
    as a real robot's message is in its own. Each :meth:`sample` is one control period.

    Args:
        sim: The plant.
        model: A :class:`SensorModel` or a preset name (default ``go2``).
        seed: Seed of the noise and the starting biases.
        leg_order: The feet's order in the record (default ``LEGS``: FL, FR, RL, RR).
    """

    def __init__(self, sim: Go2Simulator, model: SensorModel | str = DEFAULT_SENSORS, *,
                 seed: int = 0, leg_order: Sequence[str] = LEGS):
        if isinstance(model, str):
            model = SensorModel.preset(model)
        elif not isinstance(model, SensorModel):
            raise ConfigurationError(
                f"sensors: expected a SensorModel or a preset name "
                f"({', '.join(SENSOR_PRESETS)}), received {model!r}")
        legs = [check_name("leg", leg, LEGS) for leg in leg_order]
        if sorted(legs) != sorted(LEGS):
            raise ConfigurationError(
                f"leg_order: expected each of {', '.join(LEGS)} once, received {list(leg_order)}")
        self.sim = sim
        self.model = model
        self.seed = seed
        self.leg_order: tuple[str, ...] = tuple(legs)
        self._leg_rows = np.array([LEGS.index(leg) for leg in legs], dtype=np.intp)
        self._joint_qpos = np.ascontiguousarray(sim.actuator_qpos, dtype=np.intp)
        self._joint_dof = np.ascontiguousarray(sim.actuator_dof, dtype=np.intp)
        from wbc.model.leg_kinematics import LegKinematics

        self._imu_offset = LegKinematics(sim.description).imu_offset.copy()
        self._qpos, self._qvel = sim.qpos, sim.qvel  # live views: MjData's arrays never move
        self._torque, self._touch = sim.actuator_torque(), sim.foot_normal_forces()
        self._params = sampler_params(model)
        self._sites = SensorSites(self._joint_qpos, self._joint_dof, self._leg_rows,
                                  self._imu_offset)
        # The compiled overload (no dispatcher typing each sample; float64 vectors, 'A'
        # layout): its entry point takes a per-sample group as a plain tuple, field by field.
        vector = numba.float64[:]
        self._compiled = _sample.compile((
            numba.types.NamedTuple((vector, vector, vector, vector, numba.float64,
                                    numba.boolean), PlantReading),
            numba.typeof(self._sites), numba.typeof(self._params),
            numba.types.NamedTuple((vector,) * 5, SensorDrift), vector,
            numba.types.NamedTuple((vector,) * 7, RecordArrays)))
        self._program_record: SensorRecord | None = None
        self.reset()

    def prepare(self, record: SensorRecord) -> None:
        """Bind the one compiled call to ``record`` now, not in a later sample (it loads
        compiled code, hundreds of ms in a fresh process): a robot's own buffer, filled
        every period."""
        self._bind_program(record)

    def reset(self) -> None:
        """Start again: new biases and noise from the seed, the attitude filter on the truth."""
        bound = self._program_record  # bound again below, to the new arrays
        self._rng = np.random.default_rng(self.seed)
        m = self.model
        self.gyro_bias = self._rng.normal(0.0, 1.0, 3) * m.gyro_bias_rad_s
        self.accel_bias = self._rng.normal(0.0, 1.0, 3) * m.accel_bias_m_s2
        self._attitude = self._settled_attitude()
        self._integral = np.zeros(3)
        self._site_velocity = np.zeros(3)
        self._drift = SensorDrift(self._site_velocity, self.gyro_bias, self.accel_bias,
                                  self._attitude, self._integral)
        self._has_previous = False
        self._last_s = self.sim.time_s
        self._noise = np.zeros((_NOISE_BLOCK, _CHANNELS))  # the exact model's stays zero
        self._noise_rows = list(self._noise)  # each row's view, made once (not per sample)
        self._row = _NOISE_BLOCK  # used up: the first sample refills
        # Judged once here: comparing the model with the exact preset costs tens of us.
        self._exact = m.is_exact
        self.ticks = 0
        self._program: Callable[[], None] | None = None  # the one call, bound to this record:
        self._program_record = None
        self._seen_record: SensorRecord | None = None  # the last record sampled
        self._program_arrays: tuple[np.ndarray, ...] = ()
        self._header = np.zeros(3)  # what the call reads at _DT, _HAS_PREVIOUS, _ROW
        if bound is not None:
            self._bind_program(bound)

    def _bind_program(self, record: SensorRecord) -> None:
        """The sample as one compiled call that reads every array, ``record``'s too, from a
        table of addresses (:class:`wbc.core.compiled_program.CompiledProgram`): one array
        unboxed a sample, not 21. A record of other than float64 vectors keeps the plain call."""
        arrays = (record.imu_quaternion_wxyz, record.gyroscope_rad_s, record.accelerometer_m_s2,
                  record.q, record.dq, record.tau_est, record.foot_force)
        if not all(type(a) is np.ndarray and a.dtype == np.float64 and a.ndim == 1
                   and a.flags.c_contiguous for a in arrays):
            return
        plant = PlantReading(self._qpos, self._qvel, self._torque, self._touch, 0.0, False)
        program = CompiledProgram([(_sample_from_header, (
            self._header, plant, self._sites, self._params, self._drift, self._noise,
            RecordArrays(*arrays)))])
        self._program, self._program_record, self._program_arrays = program.run, record, arrays

    def _settled_attitude(self) -> np.ndarray:
        """Where the robot's attitude filter has settled while the robot stood still before
        the controller started: its "up" on the biased accelerometer's (``(w, x, y, z)``).

        A real IMU's filter runs from power-up; at rest it tilts by about the accelerometer's
        horizontal bias over g, so the first sample is already off by that much.
        """
        truth = np.array(self.sim.data.qpos[3:7], dtype=float)
        if self.model.attitude_time_constant_s <= 0.0:
            return truth
        up = np.empty(3)
        rotate_inverse(truth, np.array([0.0, 0.0, 1.0]), up)
        measured = _GRAVITY * up + self.accel_bias
        measured /= np.linalg.norm(measured)
        axis = np.cross(up, measured)
        sine = float(np.linalg.norm(axis))
        if sine < 1e-12:
            return truth
        angle = math.atan2(sine, float(up @ measured))
        tilt = -angle * axis / sine  # body-frame rotation that turns "up" onto the measurement
        step, settled = np.empty(4), np.empty(4)
        quat_exp(tilt[0], tilt[1], tilt[2], step)
        quat_multiply(truth, step, settled)
        return settled

    def sample(self, record: SensorRecord) -> None:
        """Fill ``record`` with a sample of the plant's current state (one per period)."""
        sim = self.sim
        now = sim.time_s
        if now < self._last_s:  # the simulator was reset
            self.reset()
        if self._row == _NOISE_BLOCK:
            if not self._exact:
                self._rng.standard_normal(out=self._noise)
            self._row = 0
        arrays = self._program_arrays
        if (record is self._program_record and record.imu_quaternion_wxyz is arrays[0]
                and record.gyroscope_rad_s is arrays[1]
                and record.accelerometer_m_s2 is arrays[2] and record.q is arrays[3]
                and record.dq is arrays[4] and record.tau_est is arrays[5]
                and record.foot_force is arrays[6]):
            header = self._header  # the record's arrays are written where the table points
            header[_DT] = now - self._last_s
            header[_HAS_PREVIOUS] = self._has_previous
            header[_ROW] = self._row
            self._program()  # type: ignore[misc]  # set with its record
        else:  # a PlantReading, ..., a RecordArrays
            self._compiled((self._qpos, self._qvel, self._torque, self._touch,
                            now - self._last_s, self._has_previous), self._sites, self._params,
                           self._drift, self._noise_rows[self._row],
                           (record.imu_quaternion_wxyz, record.gyroscope_rad_s,
                            record.accelerometer_m_s2, record.q, record.dq, record.tau_est,
                            record.foot_force))
            if record is self._seen_record:  # the same record again: one call from now on
                self._bind_program(record)
            self._seen_record = record
        self._row += 1
        self._has_previous = True
        self._last_s = now
        self.ticks += 1
        record.stamp_s = now
        record.tick = self.ticks
