"""The commands a simulated GO2's ``rt/lowcmd`` reader takes each physics step, checked and
counted: :class:`CommandIntake` (part of :class:`sim.dds_bridge.DdsBridge`).

Between physics steps the bridge waits on the reader (:meth:`CommandIntake.wait_until`)
instead of sleeping: each command is taken the moment it arrives and stamped with its
arrival, as a robot's drivers receive it, and applied at the next step. The arrival is the
"received" latency of :mod:`sim.bridge_stats`; the step is its "taken" latency.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from sim.bridge_stats import BridgeStats
from wbc.robot_io.dds.cdr_codec import FrameError
from wbc.robot_io.dds.low_cmd_conversion import (
    low_cmd_fault,
    motor_command_from_low_cmd,
    sdk_command_from_low_cmd,
)
from wbc.robot_io.dds.robot_end import RobotEnd
from wbc.robot_io.motor_command import MotorCommand

#: Samples the ``rt/lowcmd`` reader holds and a physics step takes at most: 16 ms of commands
#: at 1 kHz. A step that finds it full counts it (``command_history_full``): older ones may
#: have been overwritten unseen.
COMMAND_HISTORY = 16


class CommandIntake:
    """Takes every pending ``LowCmd_`` without blocking and gives the newest valid one as
    the plant's :class:`MotorCommand`; counts each in ``stats`` and reports each rejected one
    to ``reject(reason, message)``.

    Args:
        wire: The robot's end of the topics, its ``rt/lowcmd`` reader keeping
            :data:`COMMAND_HISTORY` samples.
        stats: The bridge's counters.
        slots: For each plant motor, its ``motor_cmd`` slot (the SDK's order).
        to_plant: Description order to plant order, by joint name.
        joint_names: The plant's joints, in its order (for the messages).
        effort_limit: The plant's torque limits [N m], its order.
        reject: Called with the reason and the message of each dropped command.
    """

    def __init__(self, wire: RobotEnd, stats: BridgeStats, *, slots: np.ndarray,
                 to_plant: np.ndarray, joint_names: tuple[str, ...], effort_limit: np.ndarray,
                 reject: Callable[[str, str], None]):
        self._wire = wire
        self.stats = stats
        self._slots = slots
        self._to_plant = to_plant
        self._joint_names = joint_names
        self._effort_limit = effort_limit
        self._reject = reject
        # What arrived since the last step: (arrival [s], samples, or the FrameError of
        # bytes that did not decode).
        self._arrived: list[tuple[float, list[Any] | FrameError]] = []

    def wait_until(self, deadline_s: float, clock: Callable[[], float]) -> None:
        """Wait until ``deadline_s`` on ``clock`` [s], taking each command as it arrives
        (stamped with ``clock``); :meth:`take` checks and counts them at the next step."""
        while (remaining := deadline_s - clock()) > 0.0:
            if self._wire.wait_for_command(remaining):
                self._arrived.append((clock(), self._take_pending()))

    def take(self, now_s: float) -> MotorCommand | None:
        """Every ``LowCmd_`` that arrived since the last step (:meth:`wait_until`) or is
        pending now, checked and counted; the newest one if it is valid (a robot's KeepLast 1
        reader holds only that one): older valid ones are superseded."""
        stats = self.stats
        arrived, self._arrived = self._arrived, []
        arrived.append((now_s, self._take_pending()))
        newest = None
        for received_s, samples in arrived:
            if isinstance(samples, FrameError):  # taken from the reader anyway
                stats.commands_received += 1
                self._reject("frame", str(samples))
                continue
            stats.command_history_full += len(samples) == COMMAND_HISTORY
            for sample in samples:
                info = sample.sample_info
                if info is None or not info.valid_data:  # a writer went away: no data
                    continue
                stats.commands_received += 1
                stats.commands_superseded += newest is not None
                newest = self.checked(sample.record)
                if newest is not None:
                    stats.replied(int(sample.record["reserve"]), now_s,
                                  info.source_timestamp, received_s=received_s)
        return newest

    def _take_pending(self) -> list[Any] | FrameError:
        try:
            return self._wire.take_commands()
        except FrameError as err:
            return err

    def count_pending(self) -> None:
        """Count the commands that came after the last physics step (never applied)."""
        arrived, self._arrived = self._arrived, []
        for _, samples in [*arrived, (0.0, self._take_pending())]:
            self.stats.commands_after_stop += 1 if isinstance(samples, FrameError) else sum(
                sample.sample_info is not None and sample.sample_info.valid_data
                for sample in samples)

    def checked(self, record: np.ndarray) -> MotorCommand | None:
        """The command a driver would take from ``record`` (plant order), or ``None``
        (rejected and counted). Checked compiled first; a refused one again the slow way,
        which names the reason."""
        command = motor_command_from_low_cmd(record, slots=self._slots,
                                             effort_limit=self._effort_limit)
        if command is not None:
            return command
        fault = low_cmd_fault(record)
        if fault is not None:  # "LowCmd_.crc: expected ..."
            self._reject(fault.partition(":")[0].removeprefix("LowCmd_."), fault)
            return None
        try:
            sdk = sdk_command_from_low_cmd(record)
        except FrameError as err:
            self._reject("motor_cmd", str(err))
            return None
        command = sdk.to_motor_command().reordered(self._to_plant)
        problem = command.problems(self._effort_limit, self._joint_names)
        if problem:
            self._reject("motor_cmd", f"LowCmd_.motor_cmd: {problem}")
            return None
        return command

