"""The directory of the action servers on a domain, so that a client of an action nobody serves
can say what is served: :class:`ServedDirectory` (topic ``<prefix>/_served``, one
``ServedActions`` sample a server, kept while its writer lives).
"""

from __future__ import annotations

import uuid
from typing import Any

from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from wbc.robot_io.dds.action_endpoints import is_alive, latest_qos, served_topic_name
from wbc.robot_io.dds.action_messages import ServedActions
from wbc.robot_io.dds.domain_config import DomainHandle, delete_entities


class ServedDirectory:
    """The directory of the servers under one prefix: a server's entry (:meth:`publish`),
    or a client's view of every live entry (:meth:`reader`, :meth:`entries`)."""

    def __init__(self, endpoint: DataWriter[Any] | DataReader[Any]) -> None:
        self._endpoint: DataWriter[Any] | DataReader[Any] | None = endpoint

    @classmethod
    def publish(cls, dds: DomainHandle, prefix: str, served: dict[str, str], *,
                lease_s: float) -> ServedDirectory:
        """Write one server's entry of the directory under ``prefix``; it stays there until
        :meth:`close`.

        Args:
            dds: The server's handle of the domain (its participant).
            prefix: The topics' prefix.
            served: Action name -> interface type name (``go2_interfaces/action/HighFive``).
            lease_s: The server's liveliness lease [s].
        """
        topic: Topic[ServedActions] = Topic(dds.participant, served_topic_name(prefix),
                                            ServedActions)
        writer = DataWriter(dds.participant, topic, qos=latest_qos(lease_s))
        names: Any = sorted(served)  # an IDL sequence to type checkers
        types: Any = [served[name] for name in names]
        writer.write(ServedActions(str(uuid.uuid4()), names, types))
        return cls(writer)

    @classmethod
    def reader(cls, dds: DomainHandle, prefix: str) -> ServedDirectory:
        """A reader of the directory of the servers under ``prefix`` (:meth:`entries`)."""
        topic: Topic[ServedActions] = Topic(dds.participant, served_topic_name(prefix),
                                            ServedActions)
        return cls(DataReader(dds.participant, topic, qos=latest_qos(None)))

    def entries(self) -> list[str]:
        """What the live servers of the directory serve, as sorted ``"name (type)"`` entries
        (none for a server's entry, or once closed)."""
        reader = self._endpoint
        if not isinstance(reader, DataReader):
            return []
        entries = []
        for sample in reader.read(256):
            if sample.sample_info.valid_data and is_alive(sample):
                entries += [f"{name} ({kind})" for name, kind in
                            zip(sample.action_names, sample.action_types, strict=False)]
        return sorted(entries)

    def close(self) -> None:
        """Delete the writer (the entry leaves the directory) or the reader; idempotent."""
        endpoint, self._endpoint = self._endpoint, None
        delete_entities(endpoint)
