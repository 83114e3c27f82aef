"""The robot's end of the GO2's topic pair: ``rt/lowcmd`` read, ``rt/lowstate`` and the
simulator's truth topic written, as a GO2 (or unitree_mujoco) does: :class:`RobotEnd`.

The writers are Reliable KeepLast 1 and the command reader BestEffort
(:mod:`wbc.robot_io.dds.sdk_qos`, unitree_sdk2's channels); the reader keeps ``command_depth``
samples so that a caller taking them once a physics step can count every command, not only the
newest. A wait set on it lets the caller sleep until a command arrives. What the commands mean
(their checks, the drivers) is the caller's (:class:`sim.dds_bridge.DdsBridge`); this end only
moves them.
"""

from __future__ import annotations

from typing import Any

from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.util import duration

from wbc.robot_io.dds.controller_end import wire_topic
from wbc.robot_io.dds.domain_config import delete_entities, join_domain
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos, sdk_writer_qos
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC, SimTruthMessage
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage


class RobotEnd:
    """Reads ``rt/lowcmd`` and writes ``rt/lowstate`` and ``rt/wbc/sim/truth`` on one domain.

    Args:
        domain_id: The DDS domain (the simulator: 1 by convention).
        interface: The network interface (``lo`` for processes on one machine).
        command_depth: Commands the reader holds, and one take returns, at most.

    Raises:
        ConfigurationError: An invalid domain id, interface or depth (the valid ones named),
            the domain configured otherwise in this process, or refused by Cyclone.
    """

    def __init__(self, *, domain_id: int, interface: str, command_depth: int) -> None:
        reader_qos = sdk_reader_qos(command_depth)  # checked before joining
        self.domain_id = domain_id
        self.interface = interface
        self.command_depth = command_depth
        self._dds = join_domain(interface, domain_id=domain_id)
        try:
            participant, writer_qos = self._dds.participant, sdk_writer_qos()
            self._commands = DataReader(
                participant, wire_topic(participant, LOW_CMD_TOPIC, LowCmdMessage),
                qos=reader_qos)
            self._states = DataWriter(
                participant, wire_topic(participant, LOW_STATE_TOPIC, LowStateMessage),
                qos=writer_qos)
            self._truth = DataWriter(
                participant, wire_topic(participant, SIM_TRUTH_TOPIC, SimTruthMessage),
                qos=writer_qos)
            self._waitset = WaitSet(participant)
            self._condition = ReadCondition(
                self._commands, SampleState.Any | ViewState.Any | InstanceState.Any)
            self._waitset.attach(self._condition)
        except Exception:  # nothing left behind
            self._dds.close()
            raise

    @property
    def is_closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._dds.is_closed

    def write_state(self, message: LowStateMessage) -> None:
        """Publish one ``LowState_``."""
        self._states.write(message)

    def write_truth(self, message: SimTruthMessage) -> None:
        """Publish one truth sample."""
        self._truth.write(message)

    def take_commands(self) -> list[Any]:
        """Every ``LowCmd_`` sample the reader holds (at most ``command_depth``), oldest first,
        each a :class:`~wbc.robot_io.dds.wire_message.LowCmdMessage` with its DDS
        ``sample_info`` (``valid_data`` false: a writer went away, no data).

        Raises:
            FrameError: Bytes that do not decode as a ``LowCmd_`` (they are taken all the same).
        """
        return self._commands.take(N=self.command_depth)

    def wait_for_command(self, timeout_s: float) -> bool:
        """Block until the reader holds a sample, at most ``timeout_s`` [s]; whether it does."""
        if timeout_s > 0.0 and not self._condition.triggered:
            self._waitset.wait(duration(seconds=timeout_s))
        return bool(self._condition.triggered)

    def close(self) -> None:
        """Delete the reader and writers and leave the domain; idempotent."""
        if self._dds.is_closed:
            return
        delete_entities(self._waitset, self._condition, self._commands, self._states,
                        self._truth)
        self._dds.close()
