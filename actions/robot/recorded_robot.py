"""A recorded run played to a control loop as a robot: sensors from the log, commands kept."""

from __future__ import annotations

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_log import SensorLog
from wbc.robot_io.sensor_record import SensorRecord


class RecordedRobot:
    """A :class:`~actions.robot.robot_interface.RobotInterface` that plays a :class:`SensorLog`.

    Each :meth:`read_sensors` is the log's next tick (``None`` where the run had no sample,
    and after the log's end); the commands the loop writes are kept in :attr:`commands`,
    not applied: the controller and the estimator run open loop on what a robot measured
    once, as they would on a real robot's recording. The clock is the samples' stamps.
    No exact state: a loop on it estimates.

    Args:
        log: The recorded run.

    Example:
        >>> loop = ControlLoop(RecordedRobot(SensorLog.load("run.npz")), WholeBodyController())
        >>> while not loop.robot.robot.finished:
        ...     loop.spin_once()
    """

    joint_names = JOINT_NAMES
    leg_names = LEGS

    def __init__(self, log: SensorLog):
        if not isinstance(log, SensorLog):
            raise ConfigurationError(
                f"log: expected a SensorLog (SensorLog.load(path)), received "
                f"{type(log).__name__}")
        self.log = log
        self._next = 0
        stamps = log.arrays["sensor_stamp_s"]
        stamps = stamps[np.isfinite(stamps)]
        if stamps.size == 0:
            raise ConfigurationError("log: no tick of it has a sample")
        self._time_s = float(stamps[0])
        #: The control period [s] the samples came at (the clock's step where none came).
        self.period_s = float(np.median(np.diff(stamps))) if stamps.size > 1 else 1e-3
        #: Every command the loop wrote, in order.
        self.commands: list[MotorCommand] = []

    @property
    def time_s(self) -> float:
        """The last sample's stamp [s] (one control period on where none came)."""
        return self._time_s

    @property
    def finished(self) -> bool:
        """Every tick of the log has been read."""
        return self._next >= len(self.log)

    def read_sensors(self) -> SensorRecord | None:
        """The log's next sample (``None`` where none came, and after the end)."""
        record = None if self.finished else self.log.record(self._next)
        self._next += 1
        if record is None:
            self._time_s += self.period_s
        else:
            self._time_s = record.stamp_s
        return record

    def write_command(self, command: MotorCommand) -> None:
        """Kept in :attr:`commands`; the next tick's sample is the log's, whatever it is."""
        self.commands.append(command.copy())
