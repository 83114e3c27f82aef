"""The state estimators by name: what ``go2-wbc --estimator``, the sweeps and the benchmarks
choose from.

- ``inekf`` (the default): :class:`wbc.InvariantEkf`, a contact-aided invariant EKF that
  estimates the orientation itself from the gyroscope, the accelerometer and the stance
  feet.
- ``kf``: :class:`wbc.LinearKalmanFilter` (formerly ``StateEstimator``), the orientation
  from the IMU's attitude filter and a linear Kalman filter on the legs' kinematics (MIT
  Cheetah's, legged_control's).

Chosen by measurement (``python -m benchmarks.estimator``, docs/state-estimation.md,
"The estimators"): the invariant EKF's velocity error is a quarter of the linear filter's (0.5
against 2.0 mm/s RMS on the high five, 44 against 432 mm/s at worst through pushes), its
roll and pitch are its own rather than the IMU filter's (0.08 against 0.19 deg at most),
and its tick costs 2 us more (6.4 against 4.4 us median), within the 10 us budget.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from wbc.core.validation import check_name

if TYPE_CHECKING:  # the estimators load compiled code: imported when one is made
    from wbc.estimation.estimator_base import EstimatorBase

#: Estimator names, the default first, with what each is.
ESTIMATORS: dict[str, str] = {
    "inekf": "contact-aided invariant EKF: IMU and leg kinematics",
    "kf": "linear Kalman filter: the IMU's orientation and leg kinematics",
}
#: The estimator a control loop uses unless told otherwise.
DEFAULT_ESTIMATOR = "inekf"


def make_estimator(name: str = DEFAULT_ESTIMATOR, *, control_period_s: float = 1e-3,
                   **overrides: Any) -> EstimatorBase:
    """A new estimator of the named kind for samples every ``control_period_s`` [s].

    Raises:
        UnknownNameError: An unknown name (the message lists the valid ones).
        ConfigurationError: An unknown or out-of-range override (named).
    """
    check_name("state estimator", name, ESTIMATORS)
    if name == "inekf":
        from wbc.estimation.invariant_ekf import InvariantEkf

        return InvariantEkf(control_period_s=control_period_s, **overrides)
    from wbc.estimation.linear_kalman_filter import LinearKalmanFilter

    return LinearKalmanFilter(control_period_s=control_period_s, **overrides)
