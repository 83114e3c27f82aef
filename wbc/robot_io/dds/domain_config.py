"""The Cyclone DDS configuration that binds a domain to one network interface (``lo`` for a
simulator on this machine, the robot's Ethernet interface for a real GO2), and the one place in
a process that applies it: :func:`join_domain`.

Cyclone DDS takes one configuration per domain id and process: the first ``Domain(id, xml)``
fixes it, a second one for the same id fails while the first lives, and a participant created
while no ``Domain`` object of its id is alive falls back to the default configuration (any
interface, multicast on). So every user of a domain id in a process (the robot I/O's
``LowState_``/``LowCmd_`` readers and writers, the action bridge, an action client) joins it
through :func:`join_domain`: the first creates the ``Domain``, the others share it, the last
to close deletes it (reference counted). A request for a domain id already configured with
another interface is refused, naming both::

    with join_domain("lo", domain_id=1) as dds:
        reader = DataReader(dds.participant, Topic(dds.participant, ...))
        ...
        delete_entities(reader)        # children first; the handle then leaves the domain

Discovery trap on ``lo``: Cyclone 0.10.x (unitree_sdk2, unitree_mujoco) does not use multicast
on the loopback interface, 11.0.1 does, and by default the two never find each other. On a
loopback interface the configuration turns multicast off, which makes 11.0.1 discover the
0.10.x way (unicast to the local participant ports); on any other interface (a robot's
Ethernet) it keeps Cyclone's default, which discovery across machines needs.

cyclonedds-python has no ``close()``: an entity is deleted by its ``__del__``, which is
idempotent, so :func:`delete_entities` calls it in the order given (children before parents).
"""

from __future__ import annotations

import socket
import threading
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from cyclonedds.core import DDSException, Entity
from cyclonedds.domain import Domain, DomainParticipant

from wbc.core.errors import ConfigurationError

#: The largest domain id the default RTPS port mapping allows (7400 + 250 * id + 11 < 65536).
MAX_DOMAIN_ID = 232
#: Longest a deleted writer waits for its readers to acknowledge its last samples [ms].
#: Cyclone's default is 1 s a writer, and a reader of a peer that died never acknowledges but
#: stays matched until that peer's lease ends (10 s): closing the action bridge's five writers
#: after its client died took 5 s, and a ``LowCmd_`` writer closed after its robot bridge
#: crashed would stall the close for 1 s. A live reader acknowledges within milliseconds (on
#: loopback or a robot's Ethernet), so 200 ms still delivers the last samples to every reader
#: that can take them and bounds the wait for one that cannot.
WRITER_LINGER_MS = 200
_IFF_LOOPBACK = 0x8  # Linux's flag of a loopback interface


def host_interfaces() -> list[str]:
    """The names of this host's network interfaces, sorted."""
    return sorted(name for _, name in socket.if_nameindex())


def check_domain_id(domain_id: object) -> int:
    """Return ``domain_id`` if it is a valid DDS domain id (an int in 0..232).

    Raises:
        ConfigurationError: Not an int, or out of range.
    """
    if isinstance(domain_id, bool) or not isinstance(domain_id, int):
        raise ConfigurationError(
            f"domain_id: expected an int in 0..{MAX_DOMAIN_ID}, received {domain_id!r}")
    if not 0 <= domain_id <= MAX_DOMAIN_ID:
        raise ConfigurationError(
            f"domain_id: expected 0..{MAX_DOMAIN_ID} (the default RTPS port mapping), "
            f"received {domain_id} (the GO2 uses 0, unitree_mujoco 1)")
    return domain_id


def check_interface(interface: object) -> str:
    """Return ``interface`` if it names a network interface of this host.

    Raises:
        ConfigurationError: Not a string, or no such interface (the message lists them).
    """
    names = host_interfaces()
    if not isinstance(interface, str) or interface not in names:
        raise ConfigurationError(
            f"interface: expected one of this host's network interfaces {names}, "
            f"received {interface!r}")
    return interface


def is_loopback(interface: str) -> bool:
    """Whether ``interface`` is a loopback interface (Linux: its IFF_LOOPBACK flag; elsewhere
    a name starting with ``lo``)."""
    flags = Path("/sys/class/net") / interface / "flags"
    try:
        return bool(int(flags.read_text(), 16) & _IFF_LOOPBACK)
    except (OSError, ValueError):
        return interface.startswith("lo")


def _multicast_mode(interface: str, multicast: bool | None) -> str:
    """The ``multicast`` attribute of the interface: off on loopback by default (see the
    module docstring), Cyclone's default elsewhere, or what was asked for."""
    if multicast is None:
        return "false" if is_loopback(interface) else "default"
    return "true" if multicast else "false"


def domain_config(interface: str, *, domain_id: int, multicast: bool | None = None) -> str:
    """The Cyclone DDS XML configuration of ``domain_id`` on ``interface`` only, deleted
    writers lingering at most :data:`WRITER_LINGER_MS`.

    Args:
        interface: A network interface of this host (``"lo"``, ``"eth0"``, ...).
        domain_id: The DDS domain, 0..232 (the GO2: 0; unitree_mujoco: 1).
        multicast: Use multicast on the interface; by default off on a loopback interface
            (see the module docstring) and Cyclone's default elsewhere.

    Raises:
        ConfigurationError: An unknown interface (the valid ones listed) or a domain id out
            of range.
    """
    check_domain_id(domain_id)
    check_interface(interface)
    mode = _multicast_mode(interface, multicast)
    return (
        '<?xml version="1.0" encoding="UTF-8" ?>'
        '<CycloneDDS xmlns="https://cdds.io/config">'
        f'<Domain id="{domain_id}"><General><Interfaces>'
        f'<NetworkInterface name={quoteattr(interface)} multicast="{mode}"/>'
        "</Interfaces></General>"
        f"<Internal><WriterLingerDuration>{WRITER_LINGER_MS}ms</WriterLingerDuration></Internal>"
        "</Domain></CycloneDDS>"
    )


def delete_entities(*entities: Entity | None) -> None:
    """Delete DDS entities now, in the order given (readers and writers before their
    participant); ``None`` and already deleted entities are skipped."""
    for entity in entities:
        if entity is not None:
            entity.__del__()  # cyclonedds-python's delete: idempotent, no close() method


@dataclass
class _SharedDomain:
    """A configured domain of this process and how many open handles use it."""

    domain: Domain
    interface: str
    multicast: str  # the resolved attribute: "false", "true" or "default"
    users: int


_domains: dict[int, _SharedDomain] = {}
_domains_lock = threading.Lock()


class DomainHandle:
    """A participant in a domain configured by :func:`join_domain`, holding the domain's
    configuration for as long as it is open.

    Close it (or use it as a context manager) once the readers and writers made on
    :attr:`participant` are deleted: that deletes the participant (and whatever it still
    holds), and the domain's configuration with the last handle of its id. A handle never
    closed keeps its domain configured for the life of the process.

    Attributes:
        domain_id: The DDS domain.
        interface: The network interface the domain is bound to.
    """

    def __init__(self, domain_id: int, interface: str, participant: DomainParticipant) -> None:
        """Made by :func:`join_domain`, which has acquired the shared domain."""
        self.domain_id = domain_id
        self.interface = interface
        self._participant: DomainParticipant | None = participant

    @property
    def participant(self) -> DomainParticipant:
        """The participant, on which to make topics, readers and writers.

        Raises:
            ConfigurationError: The handle is closed.
        """
        if self._participant is None:
            raise ConfigurationError(
                f"participant: the DomainHandle of domain {self.domain_id} is closed; join the "
                "domain again (join_domain) for a new participant")
        return self._participant

    @property
    def is_closed(self) -> bool:
        """Whether :meth:`close` was called."""
        return self._participant is None

    def close(self) -> None:
        """Delete the participant (and every entity it still holds) and release the domain;
        idempotent."""
        participant, self._participant = self._participant, None
        if participant is None:
            return
        delete_entities(participant)
        _release_domain(self.domain_id)

    def __enter__(self) -> DomainHandle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self.is_closed else "open"
        return f"DomainHandle(domain_id={self.domain_id}, interface={self.interface!r}, {state})"


def join_domain(interface: str, *, domain_id: int,
                multicast: bool | None = None) -> DomainHandle:
    """Join ``domain_id`` on ``interface``: configure it (:func:`domain_config`) unless this
    process already has, and make a participant in it.

    Every handle of a domain id shares one configuration; the first configures the domain,
    the last to close releases it.

    Args:
        interface: A network interface of this host (``"lo"``, ``"eth0"``, ...).
        domain_id: The DDS domain, 0..232 (the GO2: 0; unitree_mujoco: 1).
        multicast: See :func:`domain_config`.

    Returns:
        The handle: its ``participant``, and ``close()`` to leave the domain.

    Raises:
        ConfigurationError: See :func:`domain_config`; ``domain_id`` already configured in
            this process for another interface or multicast setting (both named), or by a
            ``Domain`` made outside :func:`join_domain`; or Cyclone refused the participant.
    """
    config = domain_config(interface, domain_id=domain_id, multicast=multicast)
    _acquire_domain(domain_id, interface, _multicast_mode(interface, multicast), config)
    try:
        participant = DomainParticipant(domain_id)
    except DDSException as err:
        _release_domain(domain_id)
        raise ConfigurationError(
            f"domain_id: cannot create a participant in domain {domain_id} on interface "
            f"{interface!r} ({err})") from err
    return DomainHandle(domain_id, interface, participant)


def _acquire_domain(domain_id: int, interface: str, multicast: str, config: str) -> None:
    with _domains_lock:
        shared = _domains.get(domain_id)
        if shared is not None:
            if (shared.interface, shared.multicast) != (interface, multicast):
                held = _describe(shared.interface, shared.multicast)
                raise ConfigurationError(
                    f"interface: domain {domain_id} is already configured in this process for "
                    f"{held}, received a request for {_describe(interface, multicast)}; "
                    f"Cyclone DDS takes one configuration per domain id and process: join "
                    f"domain {domain_id} with {held}, use another domain id, or close its "
                    f"{shared.users} open DomainHandle(s) first")
            shared.users += 1
            return
        try:
            domain = Domain(domain_id, config)
        except DDSException as err:
            if err.code != DDSException.DDS_RETCODE_PRECONDITION_NOT_MET:
                raise ConfigurationError(
                    f"domain_id: Cyclone DDS refused the configuration of domain {domain_id} "
                    f"on interface {interface!r} ({err})") from err
            raise ConfigurationError(
                f"domain_id: domain {domain_id} is already configured in this process outside "
                f"join_domain (a cyclonedds Domain object of it is alive); join every user of "
                f"a domain id through join_domain, or delete that Domain first") from err
        _domains[domain_id] = _SharedDomain(domain, interface, multicast, 1)


def _describe(interface: str, multicast: str) -> str:
    return f"interface {interface!r} (multicast {multicast})"


def _release_domain(domain_id: int) -> None:
    with _domains_lock:
        shared = _domains[domain_id]
        shared.users -= 1
        if shared.users == 0:
            del _domains[domain_id]
            delete_entities(shared.domain)
