"""Sensor faults on a schedule: what a GO2's sensors do when they fail, for tests and demos.

:class:`FaultyRobot` wraps a :class:`~actions.robot.robot_interface.RobotInterface` and, while a
:class:`SensorFault` is active (from ``at_s`` for ``duration_s`` of the robot's clock),
corrupts the records it passes on (:data:`FAULT_KINDS`): a NaN or a non-unit IMU quaternion,
a NaN gyroscope, accelerometer or joint encoder, a repeated (stale) sample, no sample at
all, a foot-force sensor stuck at zero or at full scale. Commands and the exact state pass
through untouched. ``go2-wbc ... --sensor-fault KIND,AT_S,DURATION_S[,NAME]`` uses it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from actions.robot.robot_interface import RobotInterface, RobotWrapper
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, check_name
from wbc.model.description import JOINT_NAMES, LEGS
from wbc.robot_io.sensor_record import SensorRecord

#: The faults, and what each does to the records while it lasts.
FAULT_KINDS: dict[str, str] = {
    "dropout": "no sample arrives",
    "stale": "the last sample arrives again (its tick repeats)",
    "quaternion_nan": "the IMU quaternion reads NaN",
    "quaternion_not_unit": "the IMU quaternion is 1.2 times too long",
    "gyro_nan": "the gyroscope reads NaN",
    "accel_nan": "the accelerometer reads NaN",
    "joint_nan": "a joint encoder reads NaN (position and velocity)",
    "foot_zero": "a foot-force sensor reads 0",
    "foot_full_scale": "a foot-force sensor reads its full scale",
}
#: Kinds that name a foot, and the one that names a joint.
_FOOT_KINDS = ("foot_zero", "foot_full_scale")
_JOINT_KINDS = ("joint_nan",)


@dataclass(frozen=True)
class SensorFault:
    """A fault of one kind from ``at_s`` for ``duration_s`` of the robot's clock [s].

    Attributes:
        kind: One of :data:`FAULT_KINDS`.
        at_s: When it starts [s].
        duration_s: How long it lasts [s].
        name: The foot (``FL`` ... ``RR``, default ``FR``) of a foot fault, or the joint
            (default ``FR_thigh_joint``) of ``joint_nan``; unused by the others.
    """

    kind: str
    at_s: float
    duration_s: float
    name: str = ""

    def __post_init__(self) -> None:
        check_name("sensor fault", self.kind, FAULT_KINDS)
        as_float("at_s", self.at_s, low=0.0)
        as_float("duration_s", self.duration_s, low=0.0, high=3600.0)
        if self.kind in _FOOT_KINDS:
            object.__setattr__(self, "name", check_name("leg", self.name or "FR", LEGS))
        elif self.kind in _JOINT_KINDS:
            object.__setattr__(self, "name",
                               check_name("joint", self.name or "FR_thigh_joint", JOINT_NAMES))
        elif self.name:
            raise ConfigurationError(
                f"name: a {self.kind} fault names no foot or joint, received {self.name!r}")

    def active(self, now_s: float) -> bool:
        """The fault lasts at ``now_s`` [s]."""
        return self.at_s - 1e-9 <= now_s < self.at_s + self.duration_s - 1e-9

    def describe(self) -> str:
        """One line: what, when, how long."""
        what = FAULT_KINDS[self.kind].replace("a foot-force sensor", f"the {self.name} "
                                              "foot-force sensor").replace(
            "a joint encoder", f"the {self.name} encoder")
        return f"{what} from {self.at_s:g} s for {self.duration_s * 1e3:g} ms"


class FaultyRobot(RobotWrapper):
    """A robot whose sensor records are corrupted by scheduled faults (see the module).

    Args:
        robot: The robot (its own orders; names are mapped by name).
        faults: The faults.
        foot_full_scale: The foot sensors' full-scale count (a ``foot_full_scale`` fault's
            reading).
    """

    def __init__(self, robot: RobotInterface, faults: Sequence[SensorFault], *,
                 foot_full_scale: float = 1000.0):
        super().__init__(robot)
        self.faults = tuple(faults)
        for fault in self.faults:
            if not isinstance(fault, SensorFault):
                raise ConfigurationError(
                    f"faults: expected SensorFault entries, received {fault!r}")
        self.foot_full_scale = as_float("foot_full_scale", foot_full_scale)
        self._joint = {name: robot.joint_names.index(name) for name in robot.joint_names}
        self._leg = {leg: list(robot.leg_names).index(leg) for leg in robot.leg_names}
        self._delivered = SensorRecord.zeros()
        self._corrupted = SensorRecord.zeros()
        self._has_delivered = False

    def read_sensors(self) -> SensorRecord | None:
        """The robot's record, corrupted by the faults active now."""
        record = self.robot.read_sensors()
        now = self.time_s
        active = [fault for fault in self.faults if fault.active(now)]
        if record is None or not active:
            return self._deliver(record)
        kinds = {fault.kind for fault in active}
        if "dropout" in kinds:
            return None
        if "stale" in kinds and self._has_delivered:
            return self._delivered
        out = self._corrupted
        out.copy_from(record)
        for fault in active:
            if fault.kind == "quaternion_nan":
                out.imu_quaternion_wxyz[:] = np.nan
            elif fault.kind == "quaternion_not_unit":
                out.imu_quaternion_wxyz *= 1.2
            elif fault.kind == "gyro_nan":
                out.gyroscope_rad_s[:] = np.nan
            elif fault.kind == "accel_nan":
                out.accelerometer_m_s2[:] = np.nan
            elif fault.kind == "joint_nan":
                index = self._joint[fault.name]
                out.q[index] = out.dq[index] = np.nan
            elif fault.kind == "foot_zero":
                out.foot_force[self._leg[fault.name]] = 0.0
            elif fault.kind == "foot_full_scale":
                out.foot_force[self._leg[fault.name]] = self.foot_full_scale
        return self._deliver(out)

    def _deliver(self, record: SensorRecord | None) -> SensorRecord | None:
        if record is not None:
            self._delivered.copy_from(record)
            self._has_delivered = True
        return record
