"""The estimators' former home, kept so that old imports work: :class:`EstimatorBase` now
lives in :mod:`wbc.estimation.estimator_base`, and ``StateEstimator`` is the linear Kalman
filter, :class:`wbc.estimation.linear_kalman_filter.LinearKalmanFilter`."""

from __future__ import annotations

from wbc.estimation.estimator_base import EstimatorBase
from wbc.estimation.linear_kalman_filter import LinearKalmanFilter

#: The linear Kalman filter's former name.
StateEstimator = LinearKalmanFilter

__all__ = ["EstimatorBase", "LinearKalmanFilter", "StateEstimator"]
