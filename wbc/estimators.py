"""The state estimators by name: what ``go2-wbc --estimator``, the sweeps and the benchmarks
choose from.

- ``kf`` (the default): :class:`wbc.StateEstimator`, orientation from the IMU and a linear
  Kalman filter on the legs' kinematics.
- ``inekf``: :class:`wbc.invariant_ekf.InvariantEkf`, a contact-aided invariant EKF that
  estimates the orientation itself from the gyroscope and the accelerometer.

The README's "State estimation" section compares them by measurement.
"""

from __future__ import annotations

from typing import Any

from wbc.validation import check_name

#: Estimator names, the default first, with what each is.
ESTIMATORS: dict[str, str] = {
    "kf": "linear Kalman filter, IMU orientation and leg kinematics",
    "inekf": "contact-aided invariant EKF, IMU and leg kinematics",
}
#: The estimator a control loop uses unless told otherwise.
DEFAULT_ESTIMATOR = "kf"


def make_estimator(name: str = DEFAULT_ESTIMATOR, *, control_period_s: float = 1e-3,
                   **overrides: Any) -> Any:
    """A new estimator of the named kind for samples every ``control_period_s`` [s].

    Raises:
        UnknownNameError: An unknown name (the message lists the valid ones).
        ConfigurationError: An unknown or out-of-range override (named).
    """
    check_name("state estimator", name, ESTIMATORS)
    if name == "inekf":
        from wbc.invariant_ekf import InvariantEkf

        return InvariantEkf(control_period_s=control_period_s, **overrides)
    from wbc.state_estimator import StateEstimator

    return StateEstimator(control_period_s=control_period_s, **overrides)
