"""Real-time scheduling for the loops that keep a robot's clock: :class:`RealtimeScheduling`.

A 500 Hz loop on a shared machine misses its deadlines when the kernel gives its core to
another process for a few milliseconds; the staleness watchdog then damps the robot and
aborts its goal (measured on 2 cores under a load of 2: gaps of 11 to 31 ms). Robot
controllers run their loop under ``SCHED_FIFO`` for this reason (ros2_control asks for
priority 50): the loop then preempts every ordinary process the moment its sleep ends.

What runs real-time here, and when:

- **the loop thread**, at the priority asked for, and **the DDS threads that bring it its
  samples** (Cyclone's receive threads ``recv*`` and its user delivery queue ``dq.user``)
  one level above it, so that a state or command that arrived is in the reader before the
  loop looks (network before computation, as PREEMPT_RT kernels order their threads);
- **only while the loop runs**: start-up (imports, compiling, building the controller) stays
  ordinary, so that it cannot starve the other loops of the machine, and each thread gets
  its scheduling back when the loop ends. Cyclone's other threads (discovery, heartbeats,
  garbage collection) and every other thread of the process stay ordinary.

The loops sleep most of each period, and Linux keeps 5 % of every second for ordinary
processes (``sched_rt_runtime_us``), so a real-time loop cannot lock the machine up.

It needs root or ``CAP_SYS_NICE`` (``sudo setcap cap_sys_nice+ep`` on the interpreter, or
``ulimit -r``); without it nothing changes, and :meth:`Scheduling.describe` says why.
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from pathlib import Path

from wbc.core.errors import ConfigurationError

#: The controller's loop (ros2_control's default priority).
CONTROLLER_PRIORITY = 50
#: The simulated robot's physics loop, below the controller: a late physics step only delays
#: a state (the controller's alignment waits for it), a preempted controller misses a deadline.
BRIDGE_PRIORITY = 40
MAX_PRIORITY = 99
#: Name prefixes of the Cyclone DDS threads that deliver samples to the readers: one receive
#: thread (``recv``, with multicast off) or one per socket (``recvUC``, ``recvMC``), and the
#: delivery queue of user data.
IO_THREAD_PREFIXES = ("recv", "dq.user")


def check_priority(priority: int) -> int:
    """``priority`` if it is a whole number in [0, 99].

    Raises:
        ConfigurationError: Anything else (names what was received and what is valid).
    """
    if isinstance(priority, bool) or not isinstance(priority, int) or not (
            0 <= priority <= MAX_PRIORITY):
        raise ConfigurationError(
            f"priority: expected a whole number in [0, {MAX_PRIORITY}] (0: ordinary "
            f"scheduling), received {priority!r}")
    return priority


@dataclass(frozen=True)
class PromotedThread:
    """A thread made real-time: its kernel name, id and ``SCHED_FIFO`` priority."""

    name: str
    tid: int
    priority: int


@dataclass(frozen=True)
class Scheduling:
    """What :class:`RealtimeScheduling` did: the threads it made real-time (none when it
    could not or was not asked), and why not when it could not."""

    priority: int
    promoted: tuple[PromotedThread, ...] = ()
    refused: str = ""

    @property
    def realtime(self) -> bool:
        """Whether the loop thread runs under ``SCHED_FIFO``."""
        return bool(self.promoted)

    def describe(self) -> str:
        """One line for the process's output."""
        if self.realtime:
            io = sorted({(t.name, t.priority) for t in self.promoted[1:]})
            listed = ", ".join(f"{name} {priority}" for name, priority in io)
            return (f"scheduling: real-time while the loop runs, SCHED_FIFO {self.priority} "
                    f"(DDS delivery: {listed or 'no thread found'})")
        if self.priority == 0:
            return "scheduling: ordinary (--rt-priority 0)"
        return (f"scheduling: ordinary ({self.refused}; deadlines may be missed on a busy "
                "machine)")


class RealtimeScheduling:
    """A context manager: the calling thread under ``SCHED_FIFO`` at ``priority``, the DDS
    delivery threads at ``priority + 1`` (at most 99), each thread's scheduling back as it
    was on exit. All or nothing: a refusal part way leaves every thread as it was.

    Enter it in the loop's thread, after DDS has started (its threads must exist).

    Args:
        priority: ``SCHED_FIFO`` priority of the loop, 1 to 99; 0 changes nothing.
        io_threads: Name prefixes of the threads to run one level above the loop.

    Raises:
        ConfigurationError: A priority outside [0, 99].
    """

    def __init__(self, priority: int, *,
                 io_threads: tuple[str, ...] = IO_THREAD_PREFIXES) -> None:
        self.priority = check_priority(priority)
        self.io_threads = tuple(io_threads)
        self._saved: list[tuple[int, int, int]] = []  # (tid, policy, priority)

    def __enter__(self) -> Scheduling:
        return self._promote()

    def __exit__(self, *exc: object) -> None:
        self._restore()

    def _promote(self) -> Scheduling:
        if self.priority == 0:
            return Scheduling(0)
        if not hasattr(os, "sched_setscheduler"):
            return Scheduling(self.priority, refused="this system has no SCHED_FIFO")
        io_priority = min(self.priority + 1, MAX_PRIORITY)
        wanted = [PromotedThread(threading.current_thread().name, threading.get_native_id(),
                                 self.priority)]
        wanted += [PromotedThread(name, tid, io_priority) for tid, name in _threads()
                   if name.startswith(self.io_threads)]
        promoted = []
        for thread in wanted:
            try:
                saved = (thread.tid, os.sched_getscheduler(thread.tid),
                         os.sched_getparam(thread.tid).sched_priority)
                os.sched_setscheduler(thread.tid, os.SCHED_FIFO,
                                      os.sched_param(thread.priority))
            except ProcessLookupError:  # a thread that ended since it was listed
                continue
            except OSError as err:
                self._restore()
                why = ("needs root or CAP_SYS_NICE" if isinstance(err, PermissionError)
                       else f"refused: {err}")
                return Scheduling(self.priority,
                                  refused=f"SCHED_FIFO {self.priority} {why}")
            self._saved.append(saved)
            promoted.append(thread)
        return Scheduling(self.priority, tuple(promoted))

    def _restore(self) -> None:
        saved, self._saved = self._saved, []
        for tid, policy, priority in reversed(saved):
            try:
                os.sched_setscheduler(tid, policy, os.sched_param(priority))
            except OSError:  # ended, or the policy cannot be set back: nothing to undo
                continue


def thread_scheduling(tid: int | None = None) -> tuple[int, int]:
    """The scheduling policy and priority of thread ``tid`` (the calling thread: ``None``)."""
    tid = threading.get_native_id() if tid is None else tid
    return os.sched_getscheduler(tid), os.sched_getparam(tid).sched_priority


def _threads() -> list[tuple[int, str]]:
    """This process's threads, (kernel id, kernel name); none where ``/proc`` does not
    list them."""
    found = []
    tasks = Path(f"/proc/{os.getpid()}/task")
    if not tasks.is_dir():
        return found
    for task in tasks.iterdir():
        try:
            found.append((int(task.name), (task / "comm").read_text().strip()))
        except (OSError, ValueError):  # ended while listed
            continue
    return found
