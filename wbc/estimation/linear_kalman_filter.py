"""The floating base's state from what a GO2 measures: IMU, joint encoders, foot contact.

:class:`LinearKalmanFilter` (the ``kf`` estimator; ``StateEstimator`` is its former name,
kept as an alias) turns one :class:`wbc.SensorRecord` per control tick, and the
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
  verdict: its count in newtons through the calibration (``counts = offset + gain x N``,
  :attr:`EstimatorBase.foot_calibration`) above ``foot_force_on_n`` turns contact on, below
  ``foot_force_off_n`` off. Calibrated forces that contradict the robot's weight while it
  stands are a fault, and the schedule alone decides.
  A foot's measurement noise grows ``swing_noise_scale`` times as its weight goes from 1 to
  0; a foot below ``min_contact_weight`` follows the kinematics freely. Without foot sensors
  (``use_foot_force=False``, or a sensor distrusted) the schedule alone decides.

Faults: a non-finite or non-unit quaternion, a non-finite gyroscope, accelerometer or
joint reading, a repeated (stale) sample, no sample at all, a stance foot's sensor stuck on
one value, a foot sensor at full scale, foot forces that contradict the weight. The
estimate reports what it distrusts (:attr:`StateEstimate.faults`), goes on with the rest,
and says when it has had no trustworthy sample for longer than ``trust_timeout_s``
(:attr:`StateEstimate.usable`): the control loop then sends the controller's safe command.
docs/state-estimation.md, "The estimators", has the measurements behind the choices (this
filter against the contact-aided invariant EKF, :class:`wbc.InvariantEkf`, the default).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from wbc.estimation.estimator_base import EstimatorBase
from wbc.estimation.estimator_config import EstimatorConfig
from wbc.estimation.state_estimator_kernels import (
    _ALIGN,
    _BIAS,
    _QUAT,
    _STATE_SIZE,
    WORK_SHAPES,
    KalmanArrays,
    _estimate,
    _estimate_from_header,
    _start,
)
from wbc.model.description import Go2Description


class LinearKalmanFilter(EstimatorBase):
    """The base's state from a GO2's sensors by a linear Kalman filter on the IMU's
    orientation (see the module docstring).

    Args:
        config: Every number (defaults when ``None``); see :class:`EstimatorConfig`.
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of :class:`EstimatorConfig` to change.

    Example:
        >>> estimator = LinearKalmanFilter(control_period_s=2e-3)
        >>> estimator.reset(record)                       # four feet on the floor
        >>> loads = np.zeros(4)
        >>> controller.normal_force_bounds(loads)         # the contact schedule
        >>> estimate = estimator.update(record, loads)    # every tick
        >>> out = controller.step(estimate.q, estimate.v)
    """

    config_class = EstimatorConfig
    kernel = _estimate
    header_kernel = staticmethod(_estimate_from_header)
    start_kernel = staticmethod(_start)
    work_shapes = WORK_SHAPES
    # Its yaw alignment to the IMU's world is taken from the first quaternion.
    needs_quaternion_to_start = True
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

    def _filter_arrays(self) -> KalmanArrays:
        return KalmanArrays(self._state, self._x, self._P)

    def _shift_height(self, dz: float) -> None:
        self._x[2, [0, 2, 3, 4, 5]] += dz  # the IMU's height and the feet's [m]

    @property
    def gyro_bias(self) -> np.ndarray:
        """The learnt gyroscope bias [rad/s] (a copy)."""
        return self._state[_BIAS:_BIAS + 3].copy()

    @property
    def foot_positions(self) -> np.ndarray:
        """The filter's foot centres (4, 3) [m], estimator world frame (a copy)."""
        return self._x[:, 2:].T.copy()
