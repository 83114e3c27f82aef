"""A reader or a writer of one topic, for the tools that read or write a topic of their own (the
benchmarks, a monitor of the truth topic): :class:`TopicReader`, :class:`TopicWriter`.

The GO2's two ends (:mod:`wbc.robot_io.dds.controller_end`, :mod:`wbc.robot_io.dds.robot_end`)
and the actions' endpoints (:mod:`wbc.robot_io.dds.action_endpoints`) make their own; these
are for everything else, so that no module outside this package touches cyclonedds. The data
type is an ``IdlStruct`` class or a wire message (:mod:`wbc.robot_io.dds.wire_message`).
"""

from __future__ import annotations

import time
from typing import Any

from cyclonedds.core import Qos
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader

from wbc.robot_io.dds.controller_end import wire_topic
from wbc.robot_io.dds.domain_config import DomainHandle, delete_entities


class TopicReader:
    """A reader of ``name`` on ``dds``'s participant.

    Args:
        dds: The domain joined (its participant).
        name: The topic, e.g. ``"rt/wbc/sim/truth"``.
        data_type: The sample type.
        qos: The reader's QoS (:mod:`wbc.robot_io.dds.sdk_qos`); ``None``: Cyclone's default
            (Reliable, KeepLast 1).
    """

    def __init__(self, dds: DomainHandle, name: str, data_type: type, *,
                 qos: Qos | None = None) -> None:
        participant = dds.participant
        self._reader: DataReader[Any] | None = DataReader(
            participant, wire_topic(participant, name, data_type), qos=qos)
        #: Take at most ``N`` samples (each with its DDS ``sample_info``): the reader's own
        #: call, bound once so that a timed take costs what cyclonedds' does.
        self.take = self._reader.take

    def take_newest(self, max_samples: int = 4) -> Any | None:
        """The newest sample with data among those taken now (``None``: none)."""
        newest = None
        for sample in self.take(N=max_samples):
            if sample.sample_info.valid_data:
                newest = sample
        return newest

    def close(self) -> None:
        """Delete the reader; idempotent."""
        reader, self._reader = self._reader, None
        delete_entities(reader)


class TopicWriter:
    """A writer of ``name`` on ``dds``'s participant.

    Args:
        dds: The domain joined (its participant).
        name: The topic.
        data_type: The sample type.
        qos: The writer's QoS (:mod:`wbc.robot_io.dds.sdk_qos`); ``None``: Cyclone's default.
    """

    def __init__(self, dds: DomainHandle, name: str, data_type: type, *,
                 qos: Qos | None = None) -> None:
        participant = dds.participant
        self._writer: DataWriter[Any] | None = DataWriter(
            participant, wire_topic(participant, name, data_type), qos=qos)
        #: Publish one sample: the writer's own call, bound once (see :class:`TopicReader`).
        self.write = self._writer.write

    def matched_readers(self) -> int:
        """How many readers of the topic are matched."""
        writer = self._writer
        return 0 if writer is None else int(
            writer.get_publication_matched_status().current_count)

    def wait_for_reader(self, timeout_s: float) -> bool:
        """Wait until a reader is matched, at most ``timeout_s`` [s]; whether one is."""
        deadline = time.monotonic() + timeout_s
        while not self.matched_readers():
            if time.monotonic() >= deadline:
                return False
            time.sleep(1e-3)
        return True

    def close(self) -> None:
        """Delete the writer; idempotent."""
        writer, self._writer = self._writer, None
        delete_entities(writer)
