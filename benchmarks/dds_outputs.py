"""What the ``go2-wbc`` processes of :mod:`benchmarks.dds_processes` say: a goal client's
outcome, the controller's status lines, the bridge's events, both JSON reports, and the
simulator's exact state read live (:class:`TruthMonitor`)."""

from __future__ import annotations

import json
import math
import re
import textwrap
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from actions.go2.robot_context import STANDING_HEIGHT_M
from benchmarks.dds_processes import POLL_S, wait_until
from sim.dds_evaluation import LOADED_FOOT_N
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.domain_config import join_domain
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC, SimTruthMessage
from wbc.robot_io.dds.topic_endpoints import TopicReader

_FEEDBACK = re.compile(r"^Feedback \[\s*([-\d.]+) s\]: (.*)$", re.MULTILINE)
_EVENT = re.compile(r"^\[\s*([-\d.]+) s\] (.*)$", re.MULTILINE)


def read_json(path: Path | str) -> dict[str, Any]:
    """A JSON report as a dict.

    Raises:
        ConfigurationError: It cannot be read or is not a JSON object.
    """
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ConfigurationError(f"report: cannot read {str(path)!r} ({err})") from err
    if not isinstance(data, dict):
        raise ConfigurationError(f"report: expected a JSON object in {str(path)!r}")
    return data


# -- the goal client -------------------------------------------------------------------------


@dataclass
class ClientOutcome:
    """What ``go2-wbc high-five --dds`` / ``send-goal --dds`` printed about its goal."""

    #: The goal's id once accepted; the rejection's text if it was rejected.
    goal_id: str | None
    rejection: str | None
    #: ``(seconds since the goal was sent, phase)`` of each feedback line printed.
    feedback: list[tuple[float, str]]
    #: The final status's name (``SUCCEEDED``, ``CANCELED``, ``ABORTED``) and the result's
    #: ``message``; ``None`` when none was printed (killed, no result).
    status: str | None
    message: str | None
    #: It said it was interrupted (Ctrl-C) and canceled the goal.
    interrupted: bool

    @property
    def phases(self) -> list[str]:
        """The phases the feedback went through, in order."""
        return [phase for _, phase in self.feedback]


def client_outcome(text: str) -> ClientOutcome:
    """Parse a goal client's output."""
    accepted = re.search(r"^Goal accepted with ID: (\S+)", text, re.MULTILINE)
    rejected = re.search(r"^Goal was rejected (.*)$", text, re.MULTILINE)
    status = re.search(r"^Goal finished with status: (\w+)", text, re.MULTILINE)
    feedback = []
    for match in _FEEDBACK.finditer(text):
        fields = yaml.safe_load(match.group(2))
        phase = fields.get("phase", "") if isinstance(fields, dict) else ""
        feedback.append((float(match.group(1)), str(phase)))
    message = None
    block = re.search(r"^Result:\n((?:    .*\n)+)", text, re.MULTILINE)
    if block is not None:
        result = yaml.safe_load(textwrap.dedent(block.group(1)))
        if isinstance(result, dict) and "message" in result:
            message = str(result["message"])
    return ClientOutcome(
        goal_id=None if accepted is None else accepted.group(1),
        rejection=None if rejected is None else rejected.group(1), feedback=feedback,
        status=None if status is None else status.group(1), message=message,
        interrupted="Interrupted: canceling the goal" in text)


# -- the controller's status lines and the bridge's events ------------------------------------


@dataclass
class StatusLine:
    """One of ``go2-wbc run --dds``'s status lines (one a second)."""

    t_s: float
    rate_hz: float
    misses: int
    goal: str
    control: str
    phase: str

    @property
    def idle(self) -> bool:
        """No goal running or waiting."""
        return self.goal == "idle"


def status_lines(text: str) -> list[StatusLine]:
    """The controller's status lines in its output, in order."""
    lines = []
    for line in text.splitlines():
        fields = line.split(" | ")
        if len(fields) < 8 or not re.fullmatch(r"t\s+[-\d.]+ s", fields[0]):
            continue
        lines.append(StatusLine(
            t_s=float(fields[0][1:-2]), rate_hz=float(fields[1].split()[0]),
            misses=int(fields[2].split()[1]), goal=fields[6], control=fields[7],
            phase=" | ".join(fields[8:])))
    return lines


def loop_scheduling(text: str) -> str:
    """What a bridge's or controller's output says of its loop's scheduling (its
    ``scheduling: ...`` line, without the prefix), or ``not reported``."""
    for line in text.splitlines():
        if line.startswith("scheduling: "):
            return line.removeprefix("scheduling: ")
    return "not reported"


def bridge_events(text: str) -> list[tuple[float, str]]:
    """The bridge's events (``[sim time s] text``: mode changes, rejections), in order."""
    return [(float(m.group(1)), m.group(2)) for m in _EVENT.finditer(text)]


# -- the reports -------------------------------------------------------------------------------


@dataclass
class BridgeFigures:
    """The figures of a ``go2-wbc bridge --report`` (see :mod:`sim.bridge_stats`)."""

    states_published: int
    publish_rate_hz: float
    commands_received: int
    commands_applied: int
    #: Valid, but a newer one was taken in the same physics step.
    commands_superseded: int
    #: Rejected commands by reason (``crc``, ``head``, ``level_flag``, ``motor_cmd``,
    #: ``frame``).
    commands_rejected: dict[str, int]
    replies_lost: int
    replies_repeated: int
    overruns: int
    timeouts: int
    #: State -> command latency [ms]: to the reply's arrival at the bridge ("received"), to
    #: the physics step that took it ("taken"), and to the controller's write (its DDS
    #: source timestamp: "written"); ``count``, ``median``, ``p99``, ``max``, ``min``.
    received_ms: dict[str, Any]
    taken_ms: dict[str, Any]
    written_ms: dict[str, Any]
    #: The bridge's CPU time over its wall time [% of one core].
    cpu_percent: float
    wall_time_s: float
    final_mode: str
    raw: dict[str, Any] = field(repr=False)

    @property
    def rejected(self) -> int:
        """Commands rejected, every reason."""
        return sum(self.commands_rejected.values())

    @classmethod
    def read(cls, path: Path | str) -> BridgeFigures:
        """From a report file."""
        data = read_json(path)
        stats = data["stats"]
        return cls(
            states_published=stats["states_published"],
            publish_rate_hz=stats.get("publish_rate_hz") or math.nan,
            commands_received=stats["commands_received"],
            commands_applied=stats["commands_applied"],
            commands_superseded=stats["commands_superseded"],
            commands_rejected=dict(stats["commands_rejected"]),
            replies_lost=stats["replies_lost"], replies_repeated=stats["replies_repeated"],
            overruns=stats["overruns"], timeouts=stats["timeouts"],
            received_ms=dict(stats["received_ms"]), taken_ms=dict(stats["latency_ms"]),
            written_ms=dict(stats["reply_ms"]),
            cpu_percent=float(data.get("cpu_percent", math.nan)),
            wall_time_s=float(data["wall_time_s"]), final_mode=str(data["final_mode"]),
            raw=data)


@dataclass
class ControllerFigures:
    """The figures of a ``go2-wbc run --dds --report`` (see
    :meth:`actions.robot.realtime_loop.RealtimeLoop.report`)."""

    rate_hz: float
    duration_s: float
    #: The staleness watchdog's limit [s] without a fresh state.
    stale_after_s: float
    ticks: int
    deadline_misses: int
    no_fresh_state_ticks: int
    watchdog_trips: int
    #: The robot I/O's counters (``bad_frames``: states with a bad head or CRC;
    #: ``commands_sent``, ``ticks_skipped``, ...).
    robot: dict[str, int]
    #: Per series (stages, ``tick``, ``cpu``, ``latency``, ``wake``, ``align``):
    #: ``mean_ms``, ``p50_ms``, ``p99_ms``, ``max_ms``.
    series: dict[str, dict[str, float]]
    stop_reason: str
    stop_notes: list[str]
    #: Each goal's terminal event: ``t_s``, ``goal_id``, ``event``, ``detail``.
    goals: list[dict[str, Any]]
    raw: dict[str, Any] = field(repr=False)

    @property
    def miss_percent(self) -> float:
        """Deadline misses [% of ticks]."""
        return 100.0 * self.deadline_misses / self.ticks if self.ticks else math.nan

    @classmethod
    def read(cls, path: Path | str) -> ControllerFigures:
        """From a report file."""
        data = read_json(path)
        return cls(
            rate_hz=float(data["rate_hz"]), duration_s=float(data["duration_s"]),
            stale_after_s=float(data["stale_after_s"]),
            ticks=data["ticks"], deadline_misses=data["deadline_misses"],
            no_fresh_state_ticks=data["no_fresh_state_ticks"],
            watchdog_trips=data["watchdog_trips"], robot=dict(data["robot"]),
            series=dict(data["series"]), stop_reason=str(data["stop"]["reason"]),
            stop_notes=list(data["stop"]["notes"]), goals=list(data["goals"]), raw=data)


# -- the truth, live ---------------------------------------------------------------------------


def base_height_m(record: np.ndarray) -> float:
    """The base's height [m] in a ``rt/wbc/sim/truth`` record."""
    return float(record["q"][2])


def standing(record: np.ndarray, *, min_height_m: float = STANDING_HEIGHT_M,
             min_force_n: float = LOADED_FOOT_N) -> bool:
    """Every foot carries at least ``min_force_n`` [N] and the base is at least
    ``min_height_m`` [m] high (not lying on its belly)."""
    return (bool(np.min(record["foot_force_n"]) >= min_force_n)
            and base_height_m(record) >= min_height_m)


class TruthMonitor:
    """The newest sample of the bridge's ``rt/wbc/sim/truth``, read from this process.

    Args:
        domain_id: The bridge's domain; ``interface`` its interface.
    """

    def __init__(self, domain_id: int, interface: str = "lo") -> None:
        self._dds = join_domain(interface, domain_id=domain_id)
        self._reader = TopicReader(self._dds, SIM_TRUTH_TOPIC, SimTruthMessage,
                                   qos=sdk_reader_qos())
        self._latest: np.ndarray | None = None
        #: When the newest sample was taken [s] (``time.monotonic``).
        self.taken_s = math.nan

    def __enter__(self) -> TruthMonitor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def latest(self) -> np.ndarray | None:
        """The newest sample received (a copy), ``None`` before the first."""
        sample = self._reader.take_newest(4)
        if sample is not None:
            self._latest = np.array(sample.record, copy=True)
            self.taken_s = time.monotonic()
        return self._latest

    def wait_for(self, condition: Callable[[np.ndarray], bool], *, timeout_s: float,
                 what: str, hold_s: float = 0.0) -> np.ndarray:
        """Wait until ``condition`` holds on the newest sample, and has held on every sample
        looked at for ``hold_s`` [s] of simulated time; return that sample.

        Raises:
            ProcessWaitError: Not within ``timeout_s`` [s]; the message gives the newest
                sample's time, base height and foot forces.
        """
        since = [math.nan]

        def held() -> np.ndarray | None:
            record = self.latest()
            if record is None or not condition(record):
                since[0] = math.nan
                return None
            t_s = float(record["t_s"])
            if math.isnan(since[0]):
                since[0] = t_s
            return record if t_s - since[0] >= hold_s else None

        def context() -> str:
            record = self._latest
            if record is None:
                return "no truth sample received"
            return (f"newest truth: t {float(record['t_s']):.3f} s, base at "
                    f"{base_height_m(record):.3f} m, foot forces "
                    f"{np.round(record['foot_force_n'], 1).tolist()} N")

        return wait_until(held, timeout_s=timeout_s, what=what, context=context,
                          poll_s=POLL_S)

    def close(self) -> None:
        """Delete the reader and leave the domain; idempotent."""
        if not self._dds.is_closed:
            self._reader.close()
            self._dds.close()
