"""The controller's end of the GO2's topic pair: ``rt/lowstate`` read, ``rt/lowcmd`` written, as
unitree_sdk2 talks to the robot: :class:`ControllerEnd`.

The state reader is BestEffort KeepLast 1 and the command writer Reliable KeepLast 1
(:mod:`wbc.robot_io.dds.sdk_qos`): the reader holds only the newest ``LowState_``, never a
queue of stale ones. A wait set on the reader lets a caller block until a state arrives. What
the frames mean (the stream's kind, its checks, the records) is the caller's
(:class:`actions.robot.dds_robot.DdsRobot`); this end only moves them.
"""

from __future__ import annotations

import atexit
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from wbc.robot_io.dds.domain_config import delete_entities, join_domain
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos, sdk_writer_qos
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage

#: Samples one take returns at most: KeepLast 1 holds one; more only if a writer of another
#: instance appeared.
TAKE_MAX = 8


def wire_topic(participant: Any, name: str, data_type: Any) -> Topic[Any]:
    """A topic of a wire-message type (cyclonedds' type hints know only ``IdlStruct``)."""
    return Topic(participant, name, data_type)


class ControllerEnd:
    """Reads ``rt/lowstate`` (the newest only) and writes ``rt/lowcmd`` on one domain.

    Args:
        domain_id: The DDS domain (a GO2: 0; the simulator bridge: 1 by convention).
        interface: The network interface (``lo``; a GO2's Ethernet interface, e.g. ``eth0``).
        write_commands: Make the command writer; without it (a dry run) :meth:`write_command`
            sends nothing.

    Raises:
        ConfigurationError: An invalid domain id or interface (the valid ones named).
    """

    def __init__(self, *, domain_id: int, interface: str, write_commands: bool = True) -> None:
        self.domain_id = domain_id
        self.interface = interface
        self._lock = threading.Lock()  # a write from the loop, a close from another thread
        self._dds = join_domain(interface, domain_id=domain_id)
        self._writer: DataWriter | None = None
        try:
            participant = self._dds.participant
            self._reader = DataReader(
                participant, wire_topic(participant, LOW_STATE_TOPIC, LowStateMessage),
                qos=sdk_reader_qos())
            if write_commands:
                self._writer = DataWriter(
                    participant, wire_topic(participant, LOW_CMD_TOPIC, LowCmdMessage),
                    qos=sdk_writer_qos())
            self._waitset = WaitSet(participant)
            self._condition = ReadCondition(
                self._reader, SampleState.Any | ViewState.Any | InstanceState.Any)
            self._waitset.attach(self._condition)
        except BaseException:
            self._dds.close()
            raise
        atexit.register(self.close)  # readers go before the interpreter does

    @property
    def is_closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._dds.is_closed

    @property
    def state_pending(self) -> bool:
        """Whether the state reader holds a sample not yet taken (a valid one or not)."""
        return bool(self._condition.triggered)

    def take_states(self, max_samples: int = TAKE_MAX) -> Iterator[np.ndarray]:
        """The ``LowState_`` records the reader holds, oldest first, taken (not yet judged);
        samples without data (a writer that went away) are skipped."""
        for sample in self._reader.take(max_samples):
            if sample.sample_info.valid_data:
                yield sample.record

    def wait_for_state(self, timeout_s: float) -> bool:
        """Block until the reader holds a sample, at most ``timeout_s`` [s]; whether it does."""
        if timeout_s > 0.0 and not self._condition.triggered:
            self._waitset.wait(duration(seconds=timeout_s))
        return bool(self._condition.triggered)

    def write_command(self, message: LowCmdMessage) -> bool:
        """Publish ``message``; whether a reader of ``rt/lowcmd`` was matched (``False``: it
        went nowhere). Nothing is sent without a writer (a dry run, or closed): ``True``."""
        with self._lock:
            writer = self._writer
            if writer is None:
                return True
            matched = bool(writer.get_publication_matched_status().current_count)
            writer.write(message)
            return matched

    def wait_for_command_reader(self, timeout_s: float) -> bool:
        """Wait until a reader of ``rt/lowcmd`` is matched, at most ``timeout_s`` [s]; whether
        one is (``True`` without a writer: nothing to match)."""
        writer = self._writer
        if writer is None:
            return True
        deadline = time.monotonic() + timeout_s
        while not writer.get_publication_matched_status().current_count:
            if time.monotonic() >= deadline:
                return False
            time.sleep(1e-3)  # discovery on one host matches within milliseconds
        return True

    def state_writers_matched(self) -> int:
        """How many writers of ``rt/lowstate`` the reader is matched with."""
        return int(self._reader.get_subscription_matched_status().current_count)

    def close(self) -> None:
        """Delete the reader and writer and leave the domain; idempotent."""
        atexit.unregister(self.close)
        with self._lock:
            if self._dds.is_closed:
                return
            writer, self._writer = self._writer, None
            delete_entities(self._waitset, self._condition, self._reader, writer)
            self._dds.close()
