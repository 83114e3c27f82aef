"""What a robot already running a goal does with a new one: reject it, or preempt the old one."""

from __future__ import annotations

from enum import Enum


class BusyPolicy(Enum):
    """What a robot that is already running a goal does with a new one.

    Busy means: a goal is EXECUTING or CANCELING, or an accepted goal waits to start.
    """

    REJECT = "reject"
    """Reject the new goal (``RejectionCode.BUSY``), naming the running goal. The default."""
    PREEMPT = "preempt"
    """Accept the new goal and cancel the running one with reason ``"preempted by goal <id>
    (<action>)"`` (its server's cancel callback is not consulted). It unwinds, bounded by
    its server's ``max_unwind_s``; when its behaviour reports CANCELED, the goal ends ABORTED
    with ``abort_result("preempted by goal <id> (<action>)")``. (If the behaviour itself
    reports ABORTED, its own result stands; an unwind timeout's message names the
    preemption.) The new goal stays ACCEPTED and starts EXECUTING on the tick after the old
    one ended. A goal still waiting to start is aborted at once, with ``"preempted by goal
    <id> (<action>) before it started"``; it never runs. A goal already CANCELING at its
    client's request ends as that request says."""
