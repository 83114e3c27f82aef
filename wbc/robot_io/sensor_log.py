"""A run's sensor records and contact schedule, tick by tick: kept, loaded, replayed.

``go2-wbc ... --log FILE.npz`` keeps, beside the controller's state and the truth, every
sensor record the estimator read (in the description's orders) and the contact schedule it
was given. :class:`SensorLog` reads them back: an estimator can be replayed on them offline
(:meth:`SensorLog.replay`, to compare or tune estimators on one run, as a ROS bag is
replayed), and :class:`actions.robot.recorded_robot.RecordedRobot` plays them to a control loop as
a robot would.

Array names in the file (N ticks, description orders): ``sensor_stamp_s`` (N,),
``sensor_tick`` (N,), ``imu_quaternion_wxyz`` (N, 4), ``gyroscope_rad_s`` (N, 3),
``accelerometer_m_s2`` (N, 3), ``joint_q``, ``joint_dq``, ``tau_est`` (N, 12),
``foot_force`` (N, 4), ``contact_schedule`` (N, 4) [N]; a tick without a sample has NaN
stamps.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.robot_io.sensor_record import SensorRecord

#: The log's array of each record field.
RECORD_ARRAYS: dict[str, str] = {
    "stamp_s": "sensor_stamp_s", "tick": "sensor_tick",
    "imu_quaternion_wxyz": "imu_quaternion_wxyz", "gyroscope_rad_s": "gyroscope_rad_s",
    "accelerometer_m_s2": "accelerometer_m_s2", "q": "joint_q", "dq": "joint_dq",
    "tau_est": "tau_est", "foot_force": "foot_force",
}
_SHAPES = {"sensor_stamp_s": (), "sensor_tick": (), "imu_quaternion_wxyz": (4,),
           "gyroscope_rad_s": (3,), "accelerometer_m_s2": (3,), "joint_q": (12,),
           "joint_dq": (12,), "tau_est": (12,), "foot_force": (4,), "contact_schedule": (4,)}


def log_row(record: SensorRecord | None, schedule: np.ndarray) -> dict[str, Any]:
    """One tick's entries of a log: ``record`` (``None``: no sample, NaN) and the schedule."""
    row: dict[str, Any] = {"contact_schedule": np.array(schedule, dtype=float)}
    for field, name in RECORD_ARRAYS.items():
        if record is None:
            row[name] = np.full(_SHAPES[name], np.nan)
        else:
            value = getattr(record, field)
            row[name] = np.array(value, dtype=float)
    return row


@dataclass
class SensorLog:
    """The sensor records and contact schedules of a run (see the module docstring).

    Attributes:
        arrays: The arrays by name, N rows each.
    """

    arrays: Mapping[str, np.ndarray]

    def __post_init__(self) -> None:
        missing = [name for name in _SHAPES if name not in self.arrays]
        if missing:
            raise ConfigurationError(
                f"sensor log: missing arrays {missing}; a log written by go2-wbc --log (with "
                f"the state estimated) has {', '.join(_SHAPES)}")
        rows = len(self.arrays["sensor_stamp_s"])
        for name, shape in _SHAPES.items():
            array = np.asarray(self.arrays[name])
            if array.shape != (rows, *shape):
                raise ConfigurationError(
                    f"{name}: expected shape {(rows, *shape)}, received {array.shape}")

    @classmethod
    def load(cls, path: str | Path) -> SensorLog:
        """Read a ``--log`` file.

        Raises:
            ConfigurationError: It cannot be read, or lacks the sensor arrays (named).
        """
        try:
            with np.load(Path(path)) as data:
                arrays = {name: data[name] for name in data.files}
        except (OSError, ValueError) as err:
            raise ConfigurationError(f"sensor log: cannot read {str(path)!r}: {err}") from err
        return cls(arrays)

    @classmethod
    def from_rows(cls, rows: Sequence[Mapping[str, Any]]) -> SensorLog:
        """A log from :func:`log_row` rows."""
        if not rows:
            raise ConfigurationError("sensor log: expected at least one tick, received none")
        return cls({name: np.array([row[name] for row in rows]) for name in _SHAPES})

    def __len__(self) -> int:
        return len(self.arrays["sensor_stamp_s"])

    def record(self, k: int) -> SensorRecord | None:
        """Tick ``k``'s sample (``None`` where none came)."""
        stamp = float(self.arrays["sensor_stamp_s"][k])
        if not np.isfinite(stamp):
            return None
        values = {field: self.arrays[name][k] for field, name in RECORD_ARRAYS.items()}
        values["stamp_s"] = stamp
        values["tick"] = int(values["tick"])
        return SensorRecord(**values)

    def records(self) -> Iterator[tuple[SensorRecord | None, np.ndarray]]:
        """Each tick's sample (or ``None``) and contact schedule [N], in order."""
        schedules = self.arrays["contact_schedule"]
        for k in range(len(self)):
            yield self.record(k), schedules[k]

    def replay(self, estimator: Any) -> tuple[np.ndarray, np.ndarray]:
        """Start ``estimator`` on the first sample, run it on the rest with the logged
        schedule; its ``(q (N, 19), v (N, 18))`` estimate at every tick.

        Raises:
            ConfigurationError: The log does not start with a sample.
        """
        first = self.record(0)
        if first is None:
            raise ConfigurationError("sensor log: its first tick has no sample to start from")
        estimate = estimator.reset(first)
        qs, vs = [estimate.q.copy()], [estimate.v.copy()]
        for record, schedule in list(self.records())[1:]:
            estimate = estimator.update(record, schedule)
            qs.append(estimate.q.copy())
            vs.append(estimate.v.copy())
        return np.array(qs), np.array(vs)
