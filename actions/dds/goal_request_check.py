"""What a goal request from DDS must be before a server sees it, and the codes of its refusals.

:func:`check_goal_request` turns a
:class:`~wbc.robot_io.dds.action_messages.SendGoalRequest` into the goal message, or into a
:class:`~actions.responses.Rejection` that names what is wrong: the action, the interface, the
goal id, or the field of the payload (with what was received and what is valid).
"""

from __future__ import annotations

import uuid
from collections.abc import Container, Iterable
from enum import IntEnum
from typing import Any, NamedTuple

from actions.action_type import ActionType
from actions.dds.payload_codec import decode_message
from actions.responses import Rejection
from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.action_messages import SendGoalRequest


class TransportRejectionCode(IntEnum):
    """Rejection codes of goals refused by the DDS bridge itself, before any server saw them
    (beside the runner's 1 to 4 and the actions' own codes, e.g. HighFive's 10 to 12)."""

    MALFORMED_GOAL = 100
    """The goal payload is not JSON of the goal's fields, or a field is invalid (named)."""
    UNKNOWN_ACTION = 101
    """The request names an action other than the one of the topics it came on."""
    INTERFACE_MISMATCH = 102
    """The client's interface is not the server's (e.g. a Stand goal for high_five)."""
    DUPLICATE_GOAL_ID = 103
    """The goal id is not a UUID, or was used before."""


class CheckedGoal(NamedTuple):
    """A goal request checked: the goal message, or why it is refused (exactly one is set)."""

    goal: Any
    rejection: Rejection | None


def check_goal_request(request: SendGoalRequest, *, action_name: str, action_type: ActionType,
                       topic: str, served_names: Iterable[str],
                       used_ids: Container[str]) -> CheckedGoal:
    """Check a goal request that came on the topics of ``action_name``.

    Args:
        request: The request.
        action_name: The action whose topic the request came on.
        action_type: That action's interface.
        topic: The topic, for messages.
        served_names: Every action the bridge serves, for messages.
        used_ids: The goal ids already received.
    """
    goal_id = request.goal_id
    if request.action_name != action_name:
        return _refused(TransportRejectionCode.UNKNOWN_ACTION, (
            f"goal {goal_id} is for action {request.action_name!r} but came on the topic of "
            f"'{action_name}' ({topic}); served actions: {', '.join(sorted(served_names))}"))
    if not action_type.is_named(request.action_type):
        return _refused(TransportRejectionCode.INTERFACE_MISMATCH, (
            f"action '{action_name}' serves {action_type.type_name}; the client sent a "
            f"{request.action_type or '(no type)'} goal"))
    if not _is_uuid(goal_id) or goal_id in used_ids:
        return _refused(TransportRejectionCode.DUPLICATE_GOAL_ID, (
            f"goal_id must be a fresh UUID in canonical form (e.g. {uuid.uuid4()}); received "
            f"{goal_id!r}, which is not one or was used before"))
    try:
        goal = decode_message(request.goal, action_type.goal_type,
                              what=f"goal {goal_id} for '{action_name}'")
    except ConfigurationError as err:
        return _refused(TransportRejectionCode.MALFORMED_GOAL, str(err))
    return CheckedGoal(goal, None)


def _refused(code: TransportRejectionCode, message: str) -> CheckedGoal:
    return CheckedGoal(None, Rejection(code, message))


def _is_uuid(text: str) -> bool:
    try:
        return str(uuid.UUID(text)) == text
    except ValueError:
        return False
