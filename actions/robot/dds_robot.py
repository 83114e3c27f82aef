"""A GO2 (or its simulator) on DDS as a :class:`~actions.robot.robot_interface.RobotInterface`:
``rt/lowstate`` in, ``rt/lowcmd`` out, the way unitree_sdk2 talks to the robot.

The wire (topics, QoS, reader and writer) is the controller's end of the pair,
:class:`~wbc.robot_io.dds.controller_end.ControllerEnd`; this class gives its frames meaning.

State: a BestEffort, KeepLast 1 reader (unitree_sdk2's), taken without blocking once a control
period. The reader holds only the newest ``LowState_``; :meth:`DdsRobot.read_sensors` returns it
once (``None`` when nothing new came: never a queue of stale states). Every frame goes through
a :class:`~wbc.robot_io.dds.low_state_stream.LowStateStream`: the stream's kind (a GO2 or
``go2-wbc bridge``, Unitree's C++ simulator, Unitree's Python simulator) is decided from the
first states in :meth:`DdsRobot.wait_for_first_state`, which also measures the rate and gives
the staleness limit (:attr:`DdsRobot.stale_after_s`); the CRC is checked where the stream
carries one, a new sample is told from a repeat by its tick where the tick counts and by its
content where it does not, and a frame that fits no kind, or not the stream's, is dropped and
counted with the reason.

The record's clock: ``tick`` is the robot's own ``LowState_.tick`` when it counts, else the
number of new samples since the start (the estimator tells a new sample from a repeated one
by it); ``stamp_s`` is :attr:`DdsRobot.time_s` when the sample was taken from the reader: one
monotonic clock (``time.monotonic``, from the robot object's creation) for the stamps, the
loop's time and the runner's. The robot's tick is not used as a clock: its unit differs
between a GO2 and a simulator, and it restarts with the robot.

Command: a Reliable, KeepLast 1 writer (unitree_sdk2's) of ``LowCmd_`` with the SDK's header,
``reserve`` set to the ``tick`` of the state the command answers (a bridge measures the
state-to-command latency by it) and the CRC over all of it. A frame that would fail the
robot's checks is never published. Each command is written into one reused record by a
compiled call (:class:`~wbc.robot_io.dds.low_cmd_frame.LowCmdFrame`, ~2 us); one it refuses
goes through the checked path (:class:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand`), which
names the problem. A command written while no reader of ``rt/lowcmd`` is matched goes nowhere
(before discovery matched the robot's reader, or after it left): it is counted apart
(``commands_unmatched``), and :meth:`DdsRobot.wait_for_first_state` also waits for the match.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from wbc.core.errors import ConfigurationError, WbcError
from wbc.model.description import JOINT_NAMES, LEGS
from wbc.robot_io.dds.controller_end import ControllerEnd
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.low_cmd_conversion import (
    low_cmd_fault,
    low_cmd_from_sdk_command,
    sdk_command_from_low_cmd,
)
from wbc.robot_io.dds.low_cmd_frame import LowCmdFrame
from wbc.robot_io.dds.low_state_conversion import sensor_record_from_low_state
from wbc.robot_io.dds.low_state_stream import RATE_SAMPLES, LowStateStream
from wbc.robot_io.dds.wire_message import LowCmdMessage
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.sensor_record import SensorRecord

logger = logging.getLogger(__name__)

#: Longest wait [s] for the robot's command reader after its first state (discovery on one
#: host matches both ways within milliseconds).
MATCH_WAIT_S = 1.0
#: Longest listening [s] after the first state to decide the stream's kind and measure its
#: rate on ``RATE_SAMPLES`` new states (0.1 s at 500 Hz, 0.25 s at 200 Hz).
MEASURE_WAIT_S = 1.0


class NoRobotStateError(WbcError, TimeoutError):
    """No valid ``LowState_`` came in time: no robot or bridge publishes on the domain."""


@dataclass
class DdsRobotCounters:
    """What the robot's reader and writer saw since the start (all counts)."""

    #: Valid states returned by ``read_sensors``.
    states_used: int = 0
    #: Robot ticks that were never taken (the reader holds only the newest).
    ticks_skipped: int = 0
    #: ``read_sensors`` calls that found nothing new (``None`` returned).
    no_new_state: int = 0
    #: Frames dropped: a wrong ``head`` or CRC, or not the stream's kind (the reason:
    #: ``last_fault``).
    bad_frames: int = 0
    #: Frames that repeated the last state (its tick where the tick counts, else its bytes).
    repeated_states: int = 0
    #: A state whose tick is not after the last one's (robot restarted): used, counted.
    tick_restarts: int = 0
    #: Commands published (in a dry run: built and kept), ``commands_unmatched`` included.
    commands_sent: int = 0
    #: Commands published while no reader of ``rt/lowcmd`` was matched: they went nowhere.
    commands_unmatched: int = 0
    #: Commands refused (a value the SDK's command cannot carry): nothing published.
    commands_refused: int = 0


class DdsRobot:
    """A GO2 on DDS: read the newest ``LowState_``, publish ``LowCmd_`` (see the module doc).

    Arrays are in the description's orders (:data:`~wbc.model.description.JOINT_NAMES`,
    :data:`~wbc.model.description.LEGS`): the SDK's FR, FL, RR, RL motor slots are mapped by
    joint name on the way in and out, so a ``MappedRobot`` around it copies, never reorders.

    Args:
        domain_id: The DDS domain (a GO2: 0; the simulator bridge: 1 by convention).
        interface: The network interface (``lo``; a GO2's Ethernet interface, e.g. ``eth0``).
        dry_run: Publish nothing: every command is built, checked and kept
            (:attr:`last_command`, :attr:`last_low_cmd`) for inspection.
        clock: The monotonic clock [s] (``time.monotonic``); injectable for tests.

    Raises:
        ConfigurationError: An invalid domain id or interface (the valid ones named).

    Example:
        >>> robot = DdsRobot(domain_id=1, interface="lo")
        >>> robot.wait_for_first_state(5.0); print(robot.stream.describe())
        >>> loop = ControlLoop(robot, WholeBodyController(solver={"control_period_s": 0.002}))
    """

    joint_names: tuple[str, ...] = JOINT_NAMES
    leg_names: tuple[str, ...] = LEGS

    def __init__(self, *, domain_id: int = 1, interface: str = "lo", dry_run: bool = False,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.domain_id = domain_id
        self.interface = interface
        self.dry_run = bool(dry_run)
        self._clock = clock
        self._t0 = clock()
        self.counters = DdsRobotCounters()
        #: Why the last bad frame or refused command was dropped ('' if none was).
        self.last_fault = ""
        self._record = SensorRecord.zeros()
        self._pending: np.ndarray | None = None  # a state taken while waiting, not yet read
        #: The stream's kind, checks, rate and counters (see the module doc).
        self.stream = LowStateStream()
        self._answer_tick = 0
        self._remote = bytes(40)  # the newest state's wireless_remote
        self._frame = LowCmdFrame()
        self._cmd_record = self._frame.record
        self._cmd_message = LowCmdMessage(self._cmd_record)
        self._built = False  # a command was built into the record
        #: The wire: ``rt/lowstate`` read, ``rt/lowcmd`` written (no writer in a dry run).
        self.wire = ControllerEnd(domain_id=domain_id, interface=interface,
                                  write_commands=not self.dry_run)

    # -- RobotInterface ---------------------------------------------------------------------

    @property
    def time_s(self) -> float:
        """Seconds since this object was made, on the monotonic clock."""
        return self._clock() - self._t0

    @property
    def answer_tick(self) -> int:
        """The ``tick`` of the newest state returned: what the next command's ``reserve``
        carries (0 before the first)."""
        return self._answer_tick

    @property
    def wireless_remote(self) -> bytes:
        """The 40 bytes of ``wireless_remote`` in the newest state returned (zeros before the
        first): the GO2's remote (:mod:`wbc.robot_io.wireless_remote` decodes them)."""
        return self._remote

    @property
    def last_command(self) -> SdkMotorCommand | None:
        """The last command built (published unless a dry run) as the ``LowCmd_`` carries it
        (float32 values), ``None`` before the first."""
        return sdk_command_from_low_cmd(self._cmd_record) if self._built else None

    @property
    def last_low_cmd(self) -> np.ndarray:
        """The last ``LowCmd_`` record built (published unless a dry run): a copy, padding
        bytes included (the CRC covers them; ``ndarray.copy`` does not copy them)."""
        record = self._cmd_record
        return np.ndarray((), dtype=record.dtype, buffer=bytearray(record.tobytes()))

    @property
    def stale_after_s(self) -> float:
        """The staleness limit [s] the stream's rate measured at the start gives
        (:func:`~wbc.robot_io.dds.low_state_stream.default_stale_after_s`)."""
        return self.stream.stale_after_s()

    def stale_reason(self) -> str:
        """What arrived since the last new state, when frames did, for a fault message."""
        return self.stream.stale_reason(self._clock())

    def read_sensors(self) -> SensorRecord | None:
        """The newest new state not returned before, or ``None`` (nothing new: no frame,
        repeats, or only dropped frames). The record is this object's buffer, refilled by
        the next call."""
        record = self._take_newest()
        if record is None:
            self.counters.no_new_state += 1
            return None
        self.counters.states_used += 1
        return self._sensor_record(record, out=self._record)

    def _sensor_record(self, record: np.ndarray, *,
                       out: SensorRecord | None = None) -> SensorRecord:
        """``record`` stamped now, its tick the robot's or the new samples' count (doc)."""
        self._answer_tick = int(record["tick"])
        self._remote = record["wireless_remote"].tobytes()
        sensor = sensor_record_from_low_state(record, stamp_s=self.time_s, out=out)
        kind = self.stream.kind
        if kind is not None and not kind.ticks:
            sensor.tick = self.stream.counters.new_samples
        return sensor

    def write_command(self, command: MotorCommand) -> None:
        """Publish ``command`` (description order) as a ``LowCmd_`` answering
        :attr:`answer_tick`; in a dry run, build and keep it only.

        A command the SDK's message cannot carry (a non-finite value, a negative gain) is
        refused: nothing is published (the robot's own timeout then applies), the refusal is
        counted and logged, and the loop goes on.
        """
        if not self._frame.fill(command, reserve=self._answer_tick) and (
                not self._build_checked(command)):
            return
        self._built = True
        if not self.wire.write_command(self._cmd_message):
            self.counters.commands_unmatched += 1
        self.counters.commands_sent += 1

    #: The command is built into the frame before :meth:`write_command` returns and is not
    #: kept: a ``MappedRobot`` hands it the controller's own
    #: (:class:`~actions.robot.robot_capabilities.AppliesCommandAtOnce`).
    apply_command = write_command

    # -- start-up and teardown --------------------------------------------------------------

    def wait_for_first_state(self, timeout_s: float = 5.0) -> SensorRecord:
        """Block until a valid state arrives, then listen (up to :data:`MEASURE_WAIT_S`) until
        the stream's kind is decided and its rate measured on ``RATE_SAMPLES`` new states
        (:attr:`stream`); the newest state is what the next :meth:`read_sensors` returns.
        Then wait, up to :data:`MATCH_WAIT_S` more, until the robot's command reader is matched
        (so that the first commands reach it); a robot without one is logged, not refused.

        Args:
            timeout_s: Longest wait [s, wall clock] for the state.

        Raises:
            NoRobotStateError: Nothing valid in time; the message names the topic, the domain
                and the interface, what was seen, and asks whether the bridge or robot runs.
        """
        deadline = time.monotonic() + timeout_s
        newest, stream = None, self.stream
        while True:
            record = self._take_newest()
            if record is not None:
                if newest is None:  # the first: measure from here
                    deadline = time.monotonic() + MEASURE_WAIT_S
                newest = record
            if newest is not None and (time.monotonic() >= deadline or (
                    stream.kind is not None and stream.rate_samples >= RATE_SAMPLES)):
                stream.decide()
                self._pending = newest
                self._wait_for_command_reader(MATCH_WAIT_S)
                return self._sensor_record(newest)
            remaining = deadline - time.monotonic()
            if remaining <= 0.0:
                raise NoRobotStateError(self._no_state_message(timeout_s))
            self.wire.wait_for_state(min(remaining, 0.05))

    def wait_for_new_state(self, timeout_s: float) -> bool:
        """Whether a state not yet read is waiting in the reader, waiting for one at most
        ``timeout_s`` [s]; nothing is taken (a frame that turns out bad counts as one)."""
        return self._pending is not None or self.wire.wait_for_state(timeout_s)

    def stats(self) -> dict[str, Any]:
        """The counters as a dict, and the stream's kind, rate and counters under
        ``stream`` (for reports)."""
        return {**asdict(self.counters), "stream": self.stream.report()}

    def close(self) -> None:
        """Delete the reader and writer and leave the domain; idempotent."""
        self.wire.close()

    def __enter__(self) -> DdsRobot:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- internals --------------------------------------------------------------------------

    def _build_checked(self, command: MotorCommand) -> bool:
        """Build ``command`` into the record the checked way (what :class:`LowCmdFrame` does
        not take: another dtype, or a value it refuses, which this path names); whether it
        may be published."""
        try:
            sdk = SdkMotorCommand.from_control_output(command)
        except ConfigurationError as err:
            self._refuse(f"command not sent: {err}")
            return False
        record = self._cmd_record
        record["reserve"] = self._answer_tick  # before the CRC, which covers it
        low_cmd_from_sdk_command(sdk, out=record)
        fault = low_cmd_fault(record)
        if fault is not None:  # never happens with the SDK's header; never publish one
            self._refuse(f"command not sent: {fault}")
            return False
        return True

    def _wait_for_command_reader(self, timeout_s: float) -> None:
        """Wait until a reader of ``rt/lowcmd`` is matched, at most ``timeout_s`` [s]."""
        if not self.wire.wait_for_command_reader(timeout_s):
            logger.warning("DdsRobot: no reader of %s matched %g s after the first state; "
                           "commands go nowhere until one is (counted in "
                           "commands_unmatched)", LOW_CMD_TOPIC, timeout_s)

    def _take_newest(self) -> np.ndarray | None:
        """The newest new state in the reader (or the one a wait took), without blocking;
        every frame taken is judged by :attr:`stream` (counted, dropped with its reason)."""
        newest, self._pending = self._pending, None
        stream, now = self.stream, self._clock()
        for record in self.wire.take_states():
            if stream.accept(record, now):
                newest = record
        counters, seen = self.counters, stream.counters
        if counters.bad_frames != seen.dropped:
            self.last_fault = stream.last_fault
        counters.bad_frames, counters.repeated_states = seen.dropped, seen.repeats
        counters.ticks_skipped, counters.tick_restarts = seen.ticks_skipped, seen.tick_restarts
        return newest

    def _refuse(self, reason: str) -> None:
        if not self.counters.commands_refused:
            logger.warning("DdsRobot: %s (logged once; counted in commands_refused)", reason)
        self.counters.commands_refused += 1
        self.last_fault = reason

    def _no_state_message(self, timeout_s: float) -> str:
        publishers = self.wire.state_writers_matched()
        seen = (f"{publishers} publisher(s) of {LOW_STATE_TOPIC} matched but sent no valid "
                f"state" if publishers else f"no publisher of {LOW_STATE_TOPIC} matched")
        if self.counters.bad_frames:
            seen += (f"; {self.counters.bad_frames} frame(s) dropped, the last because "
                     f"{self.last_fault}")
        return (f"no LowState_ on {LOW_STATE_TOPIC} within {timeout_s:g} s (DDS domain "
                f"{self.domain_id}, interface {self.interface!r}): {seen}. Is the bridge or "
                f"robot running? (the simulator: 'go2-wbc bridge --domain {self.domain_id} "
                f"--interface {self.interface}'; a GO2: domain 0 on the interface of its "
                "Ethernet link, with sport mode released)")
