"""Listen to a robot's DDS topics without commanding it: every ``rt/lowstate`` as it arrives,
and whoever else writes ``rt/lowcmd`` (the bring-up check, ``go2-wbc check --dds``).

Nothing is written: the listener has readers only, so a robot under another controller (its
sport mode, another ``go2-wbc run``) is not disturbed. Unlike the control loop's reader (which
keeps only the newest state), the state reader here keeps a deep history and every sample is
stamped on arrival, so the stream's rate, jitter and gaps can be measured. Frames are kept as
they came: nothing is dropped for its head or CRC (judging them is the check's job).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from cyclonedds.core import InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from wbc.core.validation import as_float
from wbc.robot_io.dds.domain_config import delete_entities, join_domain
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage

#: States held between two takes: a 1 kHz robot sends 50 in the longest wait here (50 ms).
_HISTORY = 256
_WAIT_S = 0.05


@dataclass
class ListenedStream:
    """What :meth:`StateListener.listen` heard.

    Attributes:
        arrival_s: When each state was taken from the reader [s], monotonic clock, from the
            start of the listening (``(n,)``).
        sent_s: When its writer wrote it [s], the writer's clock (DDS source timestamp), from
            the first (``(n,)``): the robot's own rhythm, free of this process's wake-ups.
        writers: Each state's writer (DDS publication handle): two robots, or a robot and a
            simulator, on one domain show as two.
        records: Each state's C-image record (``LOW_STATE_DTYPE``), in arrival order.
        listened_s: How long it listened [s].
        state_writers: Writers of ``rt/lowstate`` matched at the end.
        command_writers: Writers of ``rt/lowcmd`` matched at the end (someone else commands
            the robot: this listener writes nothing).
        commands_seen: ``LowCmd_`` samples received from them.
    """

    arrival_s: np.ndarray
    sent_s: np.ndarray
    writers: np.ndarray
    records: list[np.ndarray] = field(repr=False)
    listened_s: float
    state_writers: int
    command_writers: int
    commands_seen: int


class StateListener:
    """Readers of ``rt/lowstate`` (deep history, stamped on arrival) and ``rt/lowcmd`` on one
    DDS domain; no writer.

    Args:
        domain_id: The DDS domain (a GO2: 0; the simulator bridge: 1).
        interface: The network interface (``lo``; a GO2's Ethernet interface, e.g. ``eth0``).
        clock: The monotonic clock [s]; injectable for tests.

    Raises:
        ConfigurationError: An invalid domain id or interface (the valid ones named).
    """

    def __init__(self, *, domain_id: int, interface: str,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.domain_id = domain_id
        self.interface = interface
        self._clock = clock
        self._dds = join_domain(interface, domain_id=domain_id)
        try:
            participant = self._dds.participant
            history = sdk_reader_qos(_HISTORY)  # unitree_sdk2's reader, a deep history
            state_topic = Topic(participant, LOW_STATE_TOPIC, LowStateMessage)
            cmd_topic = Topic(participant, LOW_CMD_TOPIC, LowCmdMessage)
            self._states = DataReader(participant, state_topic, qos=history)
            self._commands = DataReader(participant, cmd_topic, qos=history)
            self._waitset = WaitSet(participant)
            self._condition = ReadCondition(
                self._states, SampleState.Any | ViewState.Any | InstanceState.Any)
            self._waitset.attach(self._condition)
        except BaseException:
            self._dds.close()
            raise

    def listen(self, seconds: float) -> ListenedStream:
        """Take every state for ``seconds`` [s, wall clock], stamping each on arrival.

        Raises:
            ConfigurationError: ``seconds`` not in (0, 600].
        """
        seconds = as_float("seconds", seconds, low=0.0, high=600.0, low_inclusive=False)
        start = self._clock()
        end = start + seconds
        arrivals: list[float] = []
        sent: list[int] = []
        writers: list[int] = []
        records: list[np.ndarray] = []
        commands = 0
        while (now := self._clock()) < end:
            self._waitset.wait(duration(seconds=min(_WAIT_S, end - now)))
            stamp = self._clock() - start
            for sample in self._states.take(_HISTORY):
                if sample.sample_info.valid_data:
                    arrivals.append(stamp)
                    sent.append(sample.sample_info.source_timestamp)
                    writers.append(sample.sample_info.publication_handle)
                    records.append(sample.record)
            commands += sum(1 for s in self._commands.take(_HISTORY)
                            if s.sample_info.valid_data)
        return ListenedStream(
            arrival_s=np.array(arrivals),
            sent_s=(np.array(sent, dtype=np.int64) - (sent[0] if sent else 0)) * 1e-9,
            writers=np.array(writers, dtype=np.uint64), records=records,
            listened_s=self._clock() - start,
            state_writers=self._states.get_subscription_matched_status().current_count,
            command_writers=self._commands.get_subscription_matched_status().current_count,
            commands_seen=commands)

    def close(self) -> None:
        """Delete the readers and leave the domain; idempotent."""
        if self._dds.is_closed:
            return
        delete_entities(self._waitset, self._condition, self._states, self._commands)
        self._dds.close()

    def __enter__(self) -> StateListener:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

