"""Real-time scheduling for the processes that keep a robot's clock: :func:`request_realtime`.

A 500 Hz loop on a shared machine misses its deadlines when the kernel gives its core to
another process for a few milliseconds; the staleness watchdog then damps the robot and
aborts its goal (measured on 2 cores under a load of 2: gaps of 11 to 31 ms). Robot
controllers run under ``SCHED_FIFO`` for this reason (ros2_control asks for priority 50 by
default): the loop then preempts every ordinary process the moment its sleep ends. The
loops here sleep most of each period, and Linux keeps 5 % of every second for ordinary
processes (``sched_rt_runtime_us``), so a real-time loop cannot lock the machine up.

It needs root or ``CAP_SYS_NICE`` (``sudo setcap cap_sys_nice+ep`` on the interpreter, or
``ulimit -r``); without it the process runs as before and says so.
"""

from __future__ import annotations

import os

from wbc.core.errors import ConfigurationError

#: The default: ordinary scheduling. Opt in with a ``SCHED_FIFO`` priority (ros2_control
#: uses 50): with the bridge and the controller both real-time on 2 cores, the three-process
#: tests met gaps of about 1 s in the states (not yet understood; see docs/dds.md).
DEFAULT_PRIORITY = 0
MAX_PRIORITY = 99


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


def request_realtime(priority: int = DEFAULT_PRIORITY) -> str:
    """Run the calling thread, and the threads it starts from now on, under ``SCHED_FIFO``.

    Call it first, before DDS or any worker starts its threads, so that they inherit it.

    Args:
        priority: ``SCHED_FIFO`` priority, 1 to 99; 0 leaves the scheduling as it is.

    Returns:
        A sentence for the process's first lines: what scheduling it runs under, and why
        not real-time when it could not be.

    Raises:
        ConfigurationError: A priority outside [0, 99].
    """
    check_priority(priority)
    if priority == 0:
        return "scheduling: ordinary (--rt-priority 0)"
    if not hasattr(os, "sched_setscheduler"):
        return "scheduling: ordinary (this system has no SCHED_FIFO)"
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    except PermissionError:
        return (f"scheduling: ordinary (SCHED_FIFO {priority} needs root or CAP_SYS_NICE; "
                "deadlines may be missed on a busy machine)")
    except OSError as err:
        return f"scheduling: ordinary (SCHED_FIFO {priority} refused: {err})"
    return f"scheduling: real-time, SCHED_FIFO priority {priority}"


def in_realtime() -> bool:
    """Whether the calling thread runs under ``SCHED_FIFO``."""
    return hasattr(os, "sched_getscheduler") and os.sched_getscheduler(0) == os.SCHED_FIFO
