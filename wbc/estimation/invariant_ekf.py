"""A contact-aided invariant EKF for the GO2's floating base: the linear filter's alternative.

:class:`InvariantEkf` has :class:`wbc.LinearKalmanFilter`'s API (``reset``, ``update``,
``estimate``, ``describe``...) and shares its sample checks, trust accounting,
contact weights, foot motion, outputs and fault text, so the two can be swapped in the
control loop and compared by measurement. The filter itself is the right-invariant EKF of
Hartley et al., "Contact-aided invariant extended Kalman filtering for robot state
estimation" (IJRR 2020), with the IMU biases appended ("imperfect InEKF"):

- **State**: the base orientation ``R``, the velocity ``v`` and position ``p`` of the IMU
  site (the URDF's ``imu`` frame, parallel to the base) and the four foot sphere centres
  ``d_i``, one element of SE_{2+4}(3); then the gyroscope and accelerometer biases. The
  error is right-invariant (27 numbers: rotation, v, p, four feet, two biases) and its
  covariance a dense 27 x 27 matrix.
- **Prediction**: the gyroscope and accelerometer less their estimated biases (gravity
  9.81 m/s^2 down). A stance foot's centre moves as its sphere rolls (``omega_foot x (0,
  0, r)``, :func:`wbc.estimation.shared_kernels.foot_motion`): a known world-frame input to
  ``d_i`` (its first-order effect on the error, ``u x`` on the rotation, is millimetres per
  second against gravity's 9.81 m/s^2 and is left out of the Jacobian). A foot whose contact
  weight is below ``min_contact_weight`` is re-initialised from the kinematics every tick:
  ``d_i = p + R y_i`` and, as the invariant error makes exact, its covariance rows are the
  position's (plus the kinematic noise).
- **Correction**: each contact foot's position in the body frame, ``y_i = R^T (d_i - p)``
  (the group's right-invariant observation: a constant Jacobian), noise
  ``kinematics_noise_rad^2 J J^T + foot_position_noise_m^2 I`` grown ``swing_noise_scale ^
  (1 - weight)`` times as the foot is unloaded, one foot at a time. Two measurements of the
  linear filter are optional here (0 turns them off): the IMU velocity from a rolling stance
  foot (``foot_velocity_noise_m_s``, a right-invariant observation too) and a stance foot's
  height on a flat floor (``foot_height_noise_m``, not invariant: its Jacobian has the foot
  position in it).

How it differs from the linear filter: the orientation is the filter's own, from the
gyroscope, gravity and the stance feet; the IMU's quaternion is only read by :meth:`reset`
(yaw 0, roll and pitch from it), so a broken quaternion never matters and the IMU's yaw
drift does not enter. Roll and pitch come from gravity through the accelerometer (which
cannot tell a small tilt from a horizontal accelerometer bias: the priors share it); the
gyroscope bias is learnt on all three axes while feet stand still (a yaw rate moves the
feet in the body frame), and the yaw itself drifts only as the feet let it. The position,
velocity, orientation and biases are one filter (the linear filter splits them into three
6-state ones, with the orientation given): a 27 x 27 covariance, propagated and corrected
with row operations only, about 6 us a tick compiled (the linear filter's kernel: 3.5 us),
with no allocation. Fault flags, contact fusion and outputs are the linear filter's
(:mod:`wbc.estimation.shared_kernels`); the filter's kernels are
:mod:`wbc.estimation.invariant_ekf_kernels` and :mod:`wbc.estimation.invariant_ekf_group`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, as_vector, known_fields_only
from wbc.estimation.estimator_base import EstimatorBase
from wbc.estimation.estimator_config import SensorTrustConfig
from wbc.estimation.invariant_ekf_group import (
    _ABIAS,
    _DIM,
    _FEET,
    _GBIAS,
    _POS,
    _QUAT,
    _VEL,
    _X_SIZE,
)
from wbc.estimation.invariant_ekf_kernels import (
    WORK_SHAPES,
    InvariantArrays,
    _estimate,
    _estimate_from_header,
    _start,
)
from wbc.model.description import Go2Description


def _rotation_wxyz(quat: np.ndarray) -> np.ndarray:
    """The rotation matrix of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = quat
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@known_fields_only("estimator parameter")
@dataclass(frozen=True)
class InvariantEkfConfig(SensorTrustConfig):
    """Every number of the invariant EKF, validated (an error names the field and its range).

    The noise densities are continuous-time: a tick of ``dt`` seconds adds ``noise^2 dt`` to
    the covariance. They are tuning numbers (they take up what the models miss), not the
    sensors' datasheet values. They start from what go2_odometry's InEKF uses on a GO2
    (gyroscope 0.01, accelerometer 0.1, bias walks 1e-5 and 1e-4, contact 1e-3, kinematics
    1e-3 rad). Measured in closed loop (high fives, three sensor seeds; velocity error RMS,
    largest roll or pitch error): those give 0.74 mm/s and 0.16 deg; a gyroscope of 0.003
    and an accelerometer-bias prior of 0.2 m/s^2 (a MEMS offset of about 20 mg) give 0.52
    mm/s and 0.055 deg; the other noises change nothing measurable within a factor of 3.
    The gyroscope-bias prior of 0.01 rad/s (a MEMS offset of about 0.5 deg/s) costs 0.02
    deg of that on the simulated GO2's small biases, but learns a 3e-3 rad/s bias in 5 s
    rather than over 30 s (1e-3 rad/s: the estimate tilted 0.35 deg meanwhile), and with
    larger biases in closed loop (5e-3 rad/s, 0.1 m/s^2) kept the raised foot within 1.9
    mm RMS of its target instead of 4.9.

    Attributes:
        gyroscope_noise: Gyroscope noise density [rad/s/sqrt(Hz)].
        accelerometer_noise: Accelerometer noise density [m/s^2/sqrt(Hz)].
        gyro_bias_noise: Random walk of the gyroscope bias [rad/s/sqrt(s)].
        accel_bias_noise: Random walk of the accelerometer bias [m/s^2/sqrt(s)].
        contact_noise: Random walk of a stance foot's centre [m/sqrt(s)] (slip, and the
            rolling the model misses).
        kinematics_noise_rad: Joint-angle noise [rad] of a foot's kinematic position (its
            covariance ``kinematics_noise_rad^2 J J^T``).
        foot_velocity_noise_m_s: Noise [m/s] of the IMU velocity from a rolling stance
            foot (0: not measured).
        foot_height_noise_m: Noise [m] of a stance foot's height above a flat floor at
            z = 0 (0: not measured).
        initial_tilt_rad: Prior standard deviation of roll and pitch at :meth:`reset` [rad]
            (they come from the IMU's attitude filter then).
        initial_gyro_bias_rad_s: Prior standard deviation of the gyroscope bias [rad/s].
        initial_accel_bias_m_s2: Prior standard deviation of the accelerometer bias
            [m/s^2].

    The shared ones are :class:`wbc.estimation.estimator_config.SensorTrustConfig`'s; here
        ``quaternion_timeout_s`` is unused: the orientation never depends on the IMU's
        quaternion after :meth:`InvariantEkf.reset`.
    """

    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "gyroscope_noise": (1e-9, 10.0), "accelerometer_noise": (1e-9, 100.0),
        "gyro_bias_noise": (1e-12, 1.0), "accel_bias_noise": (1e-12, 10.0),
        "contact_noise": (1e-9, 10.0), "kinematics_noise_rad": (0.0, 1.0),
        "foot_velocity_noise_m_s": (0.0, 10.0), "foot_height_noise_m": (0.0, 1.0),
        "initial_tilt_rad": (1e-9, 1.0), "initial_gyro_bias_rad_s": (1e-9, 1.0),
        "initial_accel_bias_m_s2": (1e-9, 10.0),
    }
    _PARAMS: ClassVar[tuple[str, ...]] = (
        "gyroscope_noise", "accelerometer_noise", "gyro_bias_noise", "accel_bias_noise",
        "contact_noise", "kinematics_noise_rad", "foot_position_noise_m",
        "foot_velocity_noise_m_s", "foot_height_noise_m", "swing_noise_scale",
        "min_contact_weight", "foot_radius_m", "quaternion_tolerance", "initial_tilt_rad",
        "initial_gyro_bias_rad_s", "initial_accel_bias_m_s2")

    gyroscope_noise: float = 0.003
    accelerometer_noise: float = 0.1
    gyro_bias_noise: float = 1e-5
    accel_bias_noise: float = 1e-4
    contact_noise: float = 1e-3
    kinematics_noise_rad: float = 1e-3
    foot_velocity_noise_m_s: float = 0.0
    foot_height_noise_m: float = 0.0
    initial_tilt_rad: float = 0.01
    initial_gyro_bias_rad_s: float = 0.01
    initial_accel_bias_m_s2: float = 0.2


class InvariantEkf(EstimatorBase):
    """The base's state from a GO2's sensors by a contact-aided invariant EKF (see the
    module docstring); the API of :class:`wbc.estimation.linear_kalman_filter.LinearKalmanFilter`.

    Args:
        config: Every number (defaults when ``None``); see :class:`InvariantEkfConfig`.
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of :class:`InvariantEkfConfig` to change.

    Example:
        >>> loop = ControlLoop.simulated(estimator=InvariantEkf())
        >>> estimator = InvariantEkf(control_period_s=2e-3)
        >>> estimator.reset(record)                       # four feet on the floor
        >>> estimate = estimator.update(record, loads)    # every tick
    """

    config_class = InvariantEkfConfig
    kernel = _estimate
    header_kernel = staticmethod(_estimate_from_header)
    start_kernel = staticmethod(_start)
    work_shapes = WORK_SHAPES
    quaternion_note = "not used after the start (the orientation is the filter's own)"
    config: InvariantEkfConfig

    def __init__(self, config: InvariantEkfConfig | None = None, *,
                 description: Go2Description | None = None, control_period_s: float = 1e-3,
                 **overrides: Any):
        super().__init__(config, description=description, control_period_s=control_period_s,
                         **overrides)
        self._x = np.zeros(_X_SIZE)
        self._x[_QUAT] = 1.0
        self._P = np.zeros((_DIM, _DIM))

    def _filter_arrays(self) -> InvariantArrays:
        return InvariantArrays(self._x, self._P)

    def _shift_height(self, dz: float) -> None:
        self._x[_POS + 2] += dz  # the IMU's height and the feet's [m]
        self._x[_FEET + 2:_FEET + 12:3] += dz

    @property
    def gyro_bias(self) -> np.ndarray:
        """The learnt gyroscope bias [rad/s] (a copy)."""
        return self._x[_GBIAS:_GBIAS + 3].copy()

    @property
    def accel_bias(self) -> np.ndarray:
        """The learnt accelerometer bias [m/s^2] (a copy)."""
        return self._x[_ABIAS:_ABIAS + 3].copy()

    def set_imu_at_rest(self, accel_bias_m_s2: np.ndarray, up_body: np.ndarray, *,
                        bias_sigma_m_s2: float = 0.005) -> float:
        """Take the accelerometer's bias and the base's tilt measured at rest on a level floor
        (:class:`actions.robot.foot_calibration.StandingCalibration`): the filter cannot tell
        a horizontal bias from a tilt, the feet's plane can.

        The bias becomes ``accel_bias_m_s2`` [m/s^2] (base frame) with a prior of
        ``bias_sigma_m_s2`` (its cross-covariances cleared), and the orientation turns, in
        the base frame, so that its "up" is ``up_body`` (the floor's normal from the feet);
        the yaw is kept.

        Returns:
            The turn [rad] the orientation took.

        Raises:
            ConfigurationError: Not started, or a bias or "up" that is not 3 finite numbers
                (an "up" of zero length).
        """
        if not self.started:
            raise ConfigurationError("InvariantEkf.set_imu_at_rest: call reset(record) first")
        bias = as_vector("accel_bias_m_s2", accel_bias_m_s2, 3)
        up = as_vector("up_body", up_body, 3)
        sigma = as_float("bias_sigma_m_s2", bias_sigma_m_s2, low=0.0, high=10.0,
                         low_inclusive=False)
        norm = float(np.linalg.norm(up))
        if norm < 1e-9:
            raise ConfigurationError(f"up_body: expected a direction, received {up.tolist()}")
        up = up / norm
        x, cov = self._x, self._P
        rows = slice(_DIM - 3, _DIM)  # the accelerometer bias' error
        cov[rows, :] = 0.0
        cov[:, rows] = 0.0
        cov[rows, rows] = np.eye(3) * sigma ** 2
        x[_ABIAS:_ABIAS + 3] = bias
        w, qx, qy, qz = x[_QUAT:_QUAT + 4]
        now_up = 2.0 * np.array([qx * qz - w * qy, qy * qz + w * qx, 0.5 - qx * qx - qy * qy])
        axis = np.cross(up, now_up)  # turns the measured "up" onto the filter's: R <- R R_b
        angle = math.atan2(float(np.linalg.norm(axis)), float(up @ now_up))
        if angle > 1e-12:
            half = 0.5 * angle
            b = np.concatenate([[math.cos(half)], math.sin(half) * axis / np.linalg.norm(axis)])
            a = x[_QUAT:_QUAT + 4].copy()
            x[_QUAT:_QUAT + 4] = [a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                                  a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                                  a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                                  a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]]
            # The whole state turns with the base about the IMU (the world turns by
            # W = R_new R_old^T): the feet keep their place in the base frame, so their
            # measurements do not pull the orientation back. (The covariance is left as it
            # is: a turn of a degree or two changes it by as little.)
            turn = _rotation_wxyz(x[_QUAT:_QUAT + 4]) @ _rotation_wxyz(a).T
            position = x[_POS:_POS + 3].copy()
            x[_VEL:_VEL + 3] = turn @ x[_VEL:_VEL + 3]
            feet = x[_FEET:_FEET + 12].reshape(4, 3)
            feet[:] = position + (feet - position) @ turn.T
        return angle

    @property
    def foot_positions(self) -> np.ndarray:
        """The filter's foot centres (4, 3) [m], estimator world frame (a copy)."""
        return self._x[_FEET:_FEET + 12].reshape(4, 3).copy()

    @property
    def covariance(self) -> np.ndarray:
        """The right-invariant error's covariance (27, 27) (a copy): rotation, IMU
        velocity, IMU position, feet FL, FR, RL, RR, gyroscope bias, accelerometer bias."""
        return self._P.copy()
