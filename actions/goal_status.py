"""Goal status codes and the legal transitions between them (ROS 2: ``action_msgs/GoalStatus``)."""

from __future__ import annotations

from enum import IntEnum

from actions.errors import IllegalTransitionError


class GoalStatus(IntEnum):
    """Status of one goal, numbered as ``action_msgs/msg/GoalStatus``.

    A rejected goal never leaves ``UNKNOWN``: ROS 2 has no REJECTED status, the rejection is
    reported in the reply to the goal request instead.
    """

    UNKNOWN = 0
    ACCEPTED = 1
    EXECUTING = 2
    CANCELING = 3
    SUCCEEDED = 4
    CANCELED = 5
    ABORTED = 6
    # action_msgs/msg/GoalStatus's constant names, so that ROS 2 code such as
    # `status == GoalStatus.STATUS_SUCCEEDED` runs as written (aliases: same members).
    STATUS_UNKNOWN = 0
    STATUS_ACCEPTED = 1
    STATUS_EXECUTING = 2
    STATUS_CANCELING = 3
    STATUS_SUCCEEDED = 4
    STATUS_CANCELED = 5
    STATUS_ABORTED = 6

    @property
    def is_terminal(self) -> bool:
        """Whether the goal has ended (``SUCCEEDED``, ``CANCELED`` or ``ABORTED``)."""
        return self in TERMINAL_STATUSES


TERMINAL_STATUSES: frozenset[GoalStatus] = frozenset(
    {GoalStatus.SUCCEEDED, GoalStatus.CANCELED, GoalStatus.ABORTED}
)

#: Every legal status change, ``old -> {new, ...}``.
#:
#: * ``UNKNOWN -> ACCEPTED``: the goal callback and the busy policy accepted the goal.
#: * ``ACCEPTED -> EXECUTING``: the goal starts on a tick when the robot is idle.
#: * ``ACCEPTED -> CANCELING``: a client cancels a goal that has not started; it then ends
#:   ``CANCELED`` on the same tick, without its behaviour ever running.
#: * ``ACCEPTED -> ABORTED``: preempted before it started, or the runner shut down.
#: * ``EXECUTING -> CANCELING``: a cancel request (or a preemption) was acknowledged.
#: * ``EXECUTING -> SUCCEEDED | ABORTED``: the behaviour finished, or failed.
#: * ``CANCELING -> CANCELED | ABORTED``: the unwind finished, failed or timed out.
#:
#: Stricter than rclpy on purpose: ``CANCELING -> SUCCEEDED`` is illegal. The behaviour is
#: told about the cancel before its next step, so it always knows it is unwinding; a goal
#: whose motion completes during the unwind ends ``CANCELED`` (its result can say that the
#: motion completed). A client that asked to cancel therefore never sees ``SUCCEEDED``.
LEGAL_TRANSITIONS: dict[GoalStatus, frozenset[GoalStatus]] = {
    GoalStatus.UNKNOWN: frozenset({GoalStatus.ACCEPTED}),
    GoalStatus.ACCEPTED: frozenset(
        {GoalStatus.EXECUTING, GoalStatus.CANCELING, GoalStatus.ABORTED}
    ),
    GoalStatus.EXECUTING: frozenset(
        {GoalStatus.CANCELING, GoalStatus.SUCCEEDED, GoalStatus.ABORTED}
    ),
    GoalStatus.CANCELING: frozenset({GoalStatus.CANCELED, GoalStatus.ABORTED}),
    GoalStatus.SUCCEEDED: frozenset(),
    GoalStatus.CANCELED: frozenset(),
    GoalStatus.ABORTED: frozenset(),
}


def legal_next_statuses(old: GoalStatus) -> frozenset[GoalStatus]:
    """Return the statuses a goal in ``old`` may move to (empty for a terminal status)."""
    return LEGAL_TRANSITIONS[GoalStatus(old)]


def check_transition(old: GoalStatus, new: GoalStatus) -> None:
    """Raise unless a goal may move from ``old`` to ``new``.

    Args:
        old: The current status.
        new: The requested status.

    Raises:
        IllegalTransitionError: The change is not in :data:`LEGAL_TRANSITIONS`; the message
            names both statuses and lists the legal next ones.
    """
    allowed = legal_next_statuses(old)
    if GoalStatus(new) in allowed:
        return
    if allowed:
        options = ", ".join(status.name for status in sorted(allowed))
        hint = f"legal next statuses from {GoalStatus(old).name}: {options}"
    else:
        hint = f"{GoalStatus(old).name} is terminal: no further status change is legal"
    raise IllegalTransitionError(
        f"illegal goal status transition {GoalStatus(old).name} -> {GoalStatus(new).name}; {hint}"
    )
