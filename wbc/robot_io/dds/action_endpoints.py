"""The DDS topics of one action, their QoS, and one side's readers and writers on them: the
transport of actions over DDS (:mod:`actions.dds` gives it meaning), :class:`ActionEndpoints`.

The payloads (goal, feedback, result) travel as JSON text (:mod:`wbc.robot_io.dds.action_messages`),
so one set of topics and types carries any action.

Topic names are the action's name under a prefix (default ``rt/wbc/action``; ``rt/`` as ROS 2
and Unitree name their topics)::

    rt/wbc/action/high_five/send_goal/request     client -> server  SendGoalRequest
    rt/wbc/action/high_five/send_goal/response    server -> client  SendGoalResponse
    rt/wbc/action/high_five/cancel_goal/request   client -> server  CancelGoalRequest
    rt/wbc/action/high_five/cancel_goal/response  server -> client  CancelGoalResponse
    rt/wbc/action/high_five/feedback              server -> client  GoalFeedback
    rt/wbc/action/high_five/status                server -> client  GoalStatusUpdate
    rt/wbc/action/high_five/result                server -> client  GoalResult
    rt/wbc/action/_served                         server -> client  ServedActions

QoS, and why:

* Requests: RELIABLE, KEEP_ALL, VOLATILE: no goal or cancel is ever dropped; a request sent
  before a server matched is not replayed to it (a client checks for a server first). The
  client's request writers offer AUTOMATIC liveliness with a short lease (``lease_s``, 0.5 s
  by default) and the server's readers request it no longer than ``client_lease_s``: when a
  client process dies its writers stop being alive within its lease, the server sees the
  client's instance (keyed by client id) become NOT_ALIVE, and cancels its goals.
* Responses (goal and cancel): RELIABLE, KEEP_LAST 16 per client, TRANSIENT_LOCAL: a response
  reaches a client even if the server's writer discovers the client's reader only after the
  request arrived (discovery is per endpoint, in each direction).
* Feedback: RELIABLE, KEEP_LAST 32, VOLATILE: a slow client loses the oldest feedback, never
  blocks the control loop; feedback is a stream, not a record.
* Status: RELIABLE, KEEP_LAST 1 per goal, TRANSIENT_LOCAL: the latest status of each goal.
* Result: pushed by the server when a goal ends (no get-result request: every client wants
  it, and pushing saves a round trip and the server's pending requests); RELIABLE, KEEP_LAST 1
  per goal, TRANSIENT_LOCAL, so it is kept for a client that matches late. The server keeps
  the status and result of its last ``retain_finished`` goals.
* Served actions: RELIABLE, KEEP_LAST 1 per server, TRANSIENT_LOCAL: a directory.

The server's writers offer AUTOMATIC liveliness with its ``lease_s`` too, so that a client
notices a server that died with its goals.
"""

from __future__ import annotations

import logging
import re
from typing import Any, NamedTuple

from cyclonedds.core import (
    DDSException,
    GuardCondition,
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from wbc.core.errors import ConfigurationError, WbcError
from wbc.core.validation import is_finite_real
from wbc.robot_io.dds.action_messages import (
    CancelGoalRequest,
    CancelGoalResponse,
    GoalFeedback,
    GoalResult,
    GoalStatusUpdate,
    SendGoalRequest,
    SendGoalResponse,
)
from wbc.robot_io.dds.domain_config import DomainHandle, delete_entities

logger = logging.getLogger(__name__)

#: Where the action topics are, by default.
DEFAULT_PREFIX = "rt/wbc/action"
#: The network interface the bridge and clients join, by default: loopback, for processes on
#: one machine (a simulator and its clients).
DEFAULT_INTERFACE = "lo"
#: History depth of the goal and cancel responses, per client [samples].
RESPONSE_DEPTH = 16
#: History depth of the feedback topic [samples].
FEEDBACK_DEPTH = 32
#: Longest a write may block on a full reliable history [s].
MAX_BLOCKING_S = 0.1
_LIVELINESS_POLICY_ID = 8  # DDS_LIVELINESS_QOS_POLICY_ID
_ANY_SAMPLE = SampleState.Any | ViewState.Any | InstanceState.Any
#: Segments of a name: letters, digits and underscores, starting with a letter.
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$")


class TopicNames(NamedTuple):
    """The seven topics of one action (see the module docstring)."""

    send_goal_request: str
    send_goal_response: str
    cancel_goal_request: str
    cancel_goal_response: str
    feedback: str
    status: str
    result: str


def check_name(kind: str, name: object) -> str:
    """``name`` if it is a valid action name or prefix: ``/``-separated segments of letters,
    digits and underscores, each starting with a letter (``high_five``, ``rt/wbc/action``).

    Raises:
        ConfigurationError: It is not; the message says what is valid.
    """
    if not isinstance(name, str) or not _NAME.match(name):
        raise ConfigurationError(
            f"{kind} must be '/'-separated segments of letters, digits and underscores, each "
            f"starting with a letter (e.g. 'high_five', 'rt/wbc/action'); received {name!r}")
    return name


def topic_names(prefix: str, action_name: str) -> TopicNames:
    """The topics of ``action_name`` under ``prefix``."""
    base = f"{check_name('prefix', prefix)}/{check_name('action_name', action_name)}"
    return TopicNames(f"{base}/send_goal/request", f"{base}/send_goal/response",
                      f"{base}/cancel_goal/request", f"{base}/cancel_goal/response",
                      f"{base}/feedback", f"{base}/status", f"{base}/result")


def served_topic_name(prefix: str) -> str:
    """The directory topic of the servers under ``prefix`` (``_served`` is no action name)."""
    return f"{check_name('prefix', prefix)}/_served"


def check_lease(name: str, value: Any) -> float:
    """A lease [s]: a finite number in [0.05, 60].

    Raises:
        ConfigurationError: It is not.
    """
    if not is_finite_real(value) or not 0.05 <= float(value) <= 60.0:
        raise ConfigurationError(
            f"{name} must be a liveliness lease in seconds in [0.05, 60] (e.g. 0.5); "
            f"received {value!r}")
    return float(value)


def _qos(*policies: Any, lease_s: float | None = None) -> Qos:
    extra = () if lease_s is None else (
        Policy.Liveliness.Automatic(lease_duration=duration(seconds=lease_s)),)
    return Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=MAX_BLOCKING_S)),
               *policies, *extra)


def request_qos(lease_s: float | None) -> Qos:
    """Goal and cancel requests; ``lease_s`` offered by a client, requested by a server."""
    return _qos(Policy.History.KeepAll, Policy.Durability.Volatile, lease_s=lease_s)


def response_qos(lease_s: float | None) -> Qos:
    """Goal and cancel responses, keyed by client."""
    return _qos(Policy.History.KeepLast(RESPONSE_DEPTH), Policy.Durability.TransientLocal,
                lease_s=lease_s)


def feedback_qos(lease_s: float | None) -> Qos:
    """Feedback: a stream, the oldest dropped first."""
    return _qos(Policy.History.KeepLast(FEEDBACK_DEPTH), Policy.Durability.Volatile,
                lease_s=lease_s)


def latest_qos(lease_s: float | None) -> Qos:
    """Status, result and the directory: the latest sample of each instance, kept for late
    readers."""
    return _qos(Policy.History.KeepLast(1), Policy.Durability.TransientLocal, lease_s=lease_s)


class DdsError(WbcError):
    """Cyclone DDS refused a write or a take (the message is Cyclone's)."""


def is_alive(sample: Any) -> bool:
    """Whether the instance of a taken ``sample`` is alive (its writer has not gone: neither
    disposed, nor lost its liveliness, nor been deleted)."""
    return bool(sample.sample_info.instance_state == InstanceState.Alive)


class ActionEndpoints:
    """One side's readers and writers on the topics of one action.

    A server reads the requests and writes the rest; a client the other way round. Made by
    :meth:`for_server` or :meth:`for_client`; :meth:`close` deletes them. A client's side also
    holds a wait set on its readers (:meth:`wait`, :meth:`wake`).

    Attributes:
        names: The topic names.
        readers: Topic role (a :class:`TopicNames` field) -> reader, for this side's inputs.
        writers: Topic role -> writer, for this side's outputs.
    """

    def __init__(self, dds: DomainHandle, prefix: str, action_name: str) -> None:
        self.names = topic_names(prefix, action_name)
        self._participant = dds.participant
        self.topics: dict[str, Topic[Any]] = {}
        self.readers: dict[str, DataReader[Any]] = {}
        self.writers: dict[str, DataWriter[Any]] = {}
        #: A condition per reader, triggered while it holds any sample (valid or a key).
        self.conditions: dict[str, ReadCondition] = {}
        self._waitset: WaitSet | None = None
        self._wait_entities: list[Any] = []

    @classmethod
    def for_server(cls, dds: DomainHandle, prefix: str, action_name: str, *,
                   lease_s: float, client_lease_s: float) -> ActionEndpoints:
        """The server's side: it requests client liveliness within ``client_lease_s`` [s] and
        offers its own with ``lease_s`` [s]."""
        ends = cls(dds, prefix, action_name)
        ends._read("send_goal_request", SendGoalRequest, request_qos(client_lease_s))
        ends._read("cancel_goal_request", CancelGoalRequest, request_qos(client_lease_s))
        ends._write("send_goal_response", SendGoalResponse, response_qos(lease_s))
        ends._write("cancel_goal_response", CancelGoalResponse, response_qos(lease_s))
        ends._write("feedback", GoalFeedback, feedback_qos(lease_s))
        ends._write("status", GoalStatusUpdate, latest_qos(lease_s))
        ends._write("result", GoalResult, latest_qos(lease_s))
        return ends

    @classmethod
    def for_client(cls, dds: DomainHandle, prefix: str, action_name: str, *,
                   lease_s: float) -> ActionEndpoints:
        """The client's side: its readers first (so that the server's replies find them), then
        its request writers, which offer liveliness with ``lease_s`` [s]; a wait set on the
        readers."""
        ends = cls(dds, prefix, action_name)
        ends._read("send_goal_response", SendGoalResponse, response_qos(None))
        ends._read("cancel_goal_response", CancelGoalResponse, response_qos(None))
        ends._read("feedback", GoalFeedback, feedback_qos(None))
        ends._read("status", GoalStatusUpdate, latest_qos(None))
        ends._read("result", GoalResult, latest_qos(None))
        ends._write("send_goal_request", SendGoalRequest, request_qos(lease_s))
        ends._write("cancel_goal_request", CancelGoalRequest, request_qos(lease_s))
        ends._waitset = WaitSet(ends._participant)
        ends._wait_entities = [GuardCondition(ends._participant)]  # wake()'s
        for condition in (*ends.conditions.values(), *ends._wait_entities):
            ends._waitset.attach(condition)
        return ends

    def write(self, role: str, sample: Any) -> None:
        """Write ``sample`` on the topic of ``role``.

        Raises:
            DdsError: Cyclone refused it (a full history past the blocking time, a deleted
                writer).
        """
        try:
            self.writers[role].write(sample)
        except DDSException as err:
            raise DdsError(str(err)) from err

    def take(self, role: str, max_samples: int) -> list[Any]:
        """Take at most ``max_samples`` samples of the topic of ``role`` (each with its
        ``sample_info``; one whose ``valid_data`` is false carries only its key).

        Raises:
            DdsError: Cyclone refused the take.
        """
        try:
            return self.readers[role].take(max_samples)
        except DDSException as err:
            raise DdsError(str(err)) from err

    def wait(self, timeout_s: float) -> None:
        """Block until a reader of a client's side holds a sample or :meth:`wake` is called,
        at most ``timeout_s`` [s]."""
        if self._waitset is not None:
            self._waitset.wait(duration(seconds=timeout_s))

    def wake(self) -> None:
        """End a :meth:`wait` now and every one after (any thread)."""
        if self._wait_entities:
            self._wait_entities[-1].set(True)

    def alive_writers(self, role: str) -> int:
        """How many matched writers of the topic of ``role`` are alive (their liveliness
        asserted within their lease)."""
        return int(self.readers[role].get_liveliness_changed_status().alive_count)

    def liveliness_refused(self, role: str) -> bool:
        """Whether the last reader that refused the writer of ``role`` refused its liveliness
        (a lease longer than it requests)."""
        status = self.writers[role].get_offered_incompatible_qos_status()
        return bool(status.total_count and status.last_policy_id == _LIVELINESS_POLICY_ID)

    def unmatched(self) -> list[str]:
        """The roles of this side's endpoints that match no endpoint of the other side yet."""
        missing = [role for role, reader in self.readers.items()
                   if not reader.get_matched_publications()]
        missing += [role for role, writer in self.writers.items()
                    if not writer.get_matched_subscriptions()]
        return missing

    def close(self) -> None:
        """Delete the wait set, readers, writers and topics; idempotent."""
        delete_entities(self._waitset, *self._wait_entities, *self.conditions.values(),
                        *self.readers.values(), *self.writers.values(), *self.topics.values())
        self._waitset, self._wait_entities, self.conditions = None, [], {}
        self.readers, self.writers, self.topics = {}, {}, {}

    def _topic(self, role: str, data_type: type) -> Topic[Any]:
        topic: Topic[Any] = Topic(self._participant, getattr(self.names, role), data_type)
        self.topics[role] = topic
        return topic

    def _read(self, role: str, data_type: type, qos: Qos) -> None:
        reader = DataReader(self._participant, self._topic(role, data_type), qos=qos)
        self.readers[role] = reader
        self.conditions[role] = ReadCondition(reader, _ANY_SAMPLE)

    def _write(self, role: str, data_type: type, qos: Qos) -> None:
        self.writers[role] = DataWriter(self._participant, self._topic(role, data_type), qos=qos)


class SampleWatch:
    """Whether any of the readers of several :class:`ActionEndpoints` holds a sample, in one
    call: a wait set over their conditions. A server polling every control tick with nothing
    to take then pays one call, not a take per reader.

    Args:
        participant: The participant of the endpoints watched.
    """

    def __init__(self, participant: Any) -> None:
        self._waitset: WaitSet | None = WaitSet(participant)

    def watch(self, ends: ActionEndpoints) -> None:
        """Watch every reader of ``ends``."""
        if self._waitset is not None:
            for condition in ends.conditions.values():
                self._waitset.attach(condition)

    def pending(self) -> bool:
        """Whether a watched reader holds a sample now (``True`` when the wait set fails or is
        closed: the caller then takes, as without a watch)."""
        try:
            return self._waitset is None or self._waitset.wait(0) > 0
        except DDSException:
            logger.exception("SampleWatch: the wait set failed; taking anyway")
            return True

    def close(self) -> None:
        """Delete the wait set (before the endpoints' conditions); idempotent."""
        delete_entities(self._waitset)
        self._waitset = None


def write_logged(ends: ActionEndpoints, role: str, sample: Any) -> None:
    """Write ``sample`` on ``role``; a DDS error is logged, not raised (the control loop goes
    on)."""
    try:
        ends.write(role, sample)
    except DdsError:
        logger.exception("writing %r failed", sample)


def unregister_instance(ends: ActionEndpoints, role: str, sample: Any) -> None:
    """Unregister the instance of ``sample``'s key on ``role`` (its history is dropped);
    nothing if the writer never wrote it."""
    try:
        ends.writers[role].unregister_instance(sample)
    except DDSException:
        pass
