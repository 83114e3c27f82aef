"""One sample of what a GO2 measures: IMU, joint encoders and torques, foot-force counts.

A :class:`SensorRecord` is what ``rt/lowstate`` carries that a controller can use, as NumPy
arrays. It holds no base position and no linear velocity: a GO2 measures neither, and the
state estimator (:class:`wbc.StateEstimator`) turns a stream of these records into the
controller's ``(q, v)``. A simulator, a recorded log and a real robot (through
:meth:`wbc.SdkLowState.sensor_record`) all hand the control loop records like this one.

Fields and units:

- ``stamp_s`` [s]: the robot's clock when the sample was taken.
- ``tick``: a counter the robot increments with each new sample (``LowState_.tick``); a
  record with the previous record's tick is stale (the same sample again).
- ``imu_quaternion_wxyz`` (4,): the IMU's attitude filter output, ``R_world_imu`` as
  ``(w, x, y, z)`` (the GO2's IMU frame is parallel to the base frame).
- ``gyroscope_rad_s`` (3,) [rad/s]: angular velocity, IMU (= base) frame.
- ``accelerometer_m_s2`` (3,) [m/s^2]: specific force at the IMU, IMU frame (+9.81 on z
  when standing level and still).
- ``q`` [rad], ``dq`` [rad/s], ``tau_est`` [N m] (12,): per joint, in ``orders.joint_names``.
- ``foot_force`` (4,): raw foot-force counts (no unit), in ``orders.leg_names``.
- ``orders``: the record's joint and leg orders (:class:`wbc.model.orders.Orders`). A robot
  fills its records in its own orders (``SensorRecord.zeros(orders=...)``);
  :class:`actions.MappedRobot` checks them against the robot's declared ``joint_names`` and
  ``leg_names`` and hands the estimator a record in the description's orders, which the
  estimator checks in turn. A record built without orders is in the description's
  (:data:`~wbc.model.orders.DESCRIPTION_ORDERS`): that is what every consumer of records in
  the library takes, and what records built by hand for the estimator always were; a record
  in another order must say so where its arrays are filled, so that it is refused, never
  reordered twice or not at all, wherever it is passed by mistake.

Values may be non-finite: a sensor that fails sends what it sends, and the estimator
reports what it distrusts instead of stopping the loop. Shapes are checked on construction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_whole_number
from wbc.model.orders import DESCRIPTION_ORDERS, Orders

#: Field name -> shape of the record's arrays.
ARRAY_FIELDS: dict[str, int] = {
    "imu_quaternion_wxyz": 4, "gyroscope_rad_s": 3, "accelerometer_m_s2": 3,
    "q": 12, "dq": 12, "tau_est": 12, "foot_force": 4,
}


def _array(name: str, value: Any, size: int) -> np.ndarray:
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(
            f"{name}: expected {size} numbers, received {value!r}") from err
    if array.shape != (size,):
        raise ConfigurationError(
            f"{name}: expected an array of shape ({size},), received shape {array.shape}")
    return array


@dataclass(eq=False)
class SensorRecord:
    """One sensor sample (see the module docstring for the fields, units and orders).

    Arrays are copied on construction; :meth:`copy_from` refills a record in place (the
    control loop reuses its records: nothing is allocated per tick).

    Raises:
        ConfigurationError: An array of the wrong shape or not numeric, or a stamp or tick
            that is not a number (each named).
    """

    stamp_s: float
    tick: int
    imu_quaternion_wxyz: np.ndarray
    gyroscope_rad_s: np.ndarray
    accelerometer_m_s2: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    tau_est: np.ndarray
    foot_force: np.ndarray
    orders: Orders = DESCRIPTION_ORDERS

    def __post_init__(self) -> None:
        if not isinstance(self.orders, Orders):
            raise ConfigurationError(
                f"orders: expected an Orders (e.g. Orders.of(joint_names, leg_names), "
                f"DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS), received {self.orders!r}")
        if isinstance(self.stamp_s, bool) or not isinstance(self.stamp_s, (int, float,
                                                                         np.number)):
            raise ConfigurationError(f"stamp_s: expected a time [s], received {self.stamp_s!r}")
        self.stamp_s = float(self.stamp_s)
        self.tick = as_whole_number("tick", self.tick, "the sample counter")
        for name, size in ARRAY_FIELDS.items():
            setattr(self, name, _array(name, getattr(self, name), size))

    @classmethod
    def zeros(cls, orders: Orders = DESCRIPTION_ORDERS) -> SensorRecord:
        """A record of zeros (a level, unit quaternion) in ``orders``: a buffer to fill in
        place (a robot in the Unitree SDK's orders: ``SensorRecord.zeros(UNITREE_SDK_ORDERS)``)."""
        record = cls(0.0, 0, np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), np.zeros(3),
                     np.zeros(12), np.zeros(12), np.zeros(12), np.zeros(4), orders)
        return record

    def copy(self) -> SensorRecord:
        """A deep copy."""
        record = SensorRecord.zeros()
        record.copy_from(self)
        return record

    def copy_from(self, other: SensorRecord) -> None:
        """Overwrite this record with ``other``'s values and orders (in place)."""
        self.orders = other.orders
        self.stamp_s = other.stamp_s
        self.tick = other.tick
        self.imu_quaternion_wxyz[:] = other.imu_quaternion_wxyz
        self.gyroscope_rad_s[:] = other.gyroscope_rad_s
        self.accelerometer_m_s2[:] = other.accelerometer_m_s2
        self.q[:] = other.q
        self.dq[:] = other.dq
        self.tau_est[:] = other.tau_est
        self.foot_force[:] = other.foot_force

    def as_dict(self) -> dict[str, Any]:
        """Plain values (lists), JSON-ready."""
        values: dict[str, Any] = {"stamp_s": self.stamp_s, "tick": self.tick}
        values.update({name: getattr(self, name).tolist() for name in ARRAY_FIELDS})
        return values


def check_description_orders(record: object, reader: object, method: str) -> None:
    """Raise unless ``record``, a :class:`SensorRecord`, is in the description's orders
    (what the estimator and the controller read); anything else passes, for the caller's
    own checks to name. One identity comparison when it is.

    Args:
        record: What ``reader.method`` received.
        reader: The object reading it (its class is named in the message).
        method: The method reading it.

    Raises:
        OrderMismatchError: ``"<Reader>.<method>(record): in <its orders>, expected the
            description's ..."``.
    """
    orders = getattr(record, "orders", DESCRIPTION_ORDERS)
    if orders is not DESCRIPTION_ORDERS and isinstance(orders, Orders):
        orders.check(DESCRIPTION_ORDERS, what=f"{type(reader).__name__}.{method}(record)",
                     fix="map it by name first (a ControlLoop does, through MappedRobot, "
                         "for a robot that declares its joint_names and leg_names)")
