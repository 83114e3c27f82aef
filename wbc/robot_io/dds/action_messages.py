"""The IDL message types of actions over DDS: goal and cancel requests and responses, feedback,
status, result, and the directory of served actions.

Every message carries the goal id (a UUID in its canonical 36-character text form) and the
action name; goals, feedback and results travel as JSON text of the message's fields
(:mod:`actions.dds.payload_codec`), checked against the action's schema on both ends, so that
one set of wire types carries any ``.action``.

Keys: requests and their responses are keyed by the client's id, so that the server sees each
client as one DDS instance whose writer's liveliness tells whether the client is alive; status
and result are keyed by goal id, so that keep-last-1 history holds the latest of each goal.
Integers are signed (``int8``, ``int32``): no ``uint8`` (see GO2-DDS-FACTS: 0.10.x peers crash
on 11.0.1's TK_UINT8).
"""

# No `from __future__ import annotations`: cyclonedds resolves the field types of an IdlStruct
# from its annotations, and cannot resolve builtins (`str`) given as strings.
import struct
from dataclasses import dataclass, field
from typing import Any

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import key
from cyclonedds.idl.types import float64, int8, int32, sequence

#: IDL module of the types (their names on the wire: ``wbc_actions::SendGoalRequest`` ...).
_MODULE = "wbc_actions"
#: The encapsulation header of a little-endian XCDR1 message (plain CDR, options 0).
_XCDR1_LE = b"\x00\x01\x00\x00"
_UINT32, _FLOAT64 = struct.Struct("<I"), struct.Struct("<d")


def _put_cdr_string(out: bytearray, text: str) -> None:
    """Append a CDR string to a message (header first): its length with the NUL as a
    4-aligned uint32, its UTF-8 bytes, the NUL."""
    out += bytes(-(len(out) - len(_XCDR1_LE)) % 4)
    data = text.encode()
    out += _UINT32.pack(len(data) + 1)
    out += data
    out.append(0)


@dataclass
class SendGoalRequest(IdlStruct, typename=f"{_MODULE}::SendGoalRequest"):
    """A client's goal (ROS 2: ``SendGoal`` request).

    Attributes:
        client_id: The sending client's id (UUID text); the key.
        goal_id: The new goal's id (UUID text), chosen by the client.
        action_name: The action the goal is for, e.g. ``"high_five"``.
        action_type: The client's interface, e.g. ``"go2_interfaces/action/HighFive"``.
        goal: The goal message as JSON of its fields.
    """

    client_id: str
    key("client_id")
    goal_id: str
    action_name: str
    action_type: str
    goal: str


@dataclass
class SendGoalResponse(IdlStruct, typename=f"{_MODULE}::SendGoalResponse"):
    """The server's answer to a goal: accepted, or rejected with a code and a reason.

    Attributes:
        client_id: The client that sent the goal; the key.
        goal_id: The goal.
        action_name: Its action.
        accepted: Whether the goal was accepted.
        rejection_code: A :class:`~actions.responses.RejectionCode`, an action's own code or a
            :class:`~actions.dds.goal_request_check.TransportRejectionCode`; 0 if accepted.
        message: Why it was rejected ("" if accepted).
        stamp_s: The server's time [s] (its runner's clock, simulated or not).
    """

    client_id: str
    key("client_id")
    goal_id: str
    action_name: str
    accepted: bool
    rejection_code: int32
    message: str
    stamp_s: float64


@dataclass
class CancelGoalRequest(IdlStruct, typename=f"{_MODULE}::CancelGoalRequest"):
    """A client's request to cancel one of its goals (ROS 2: ``CancelGoal`` request).

    Attributes:
        client_id: The client; the key.
        request_id: This request's id (UUID text), echoed in the response.
        goal_id: The goal to cancel.
        action_name: Its action.
    """

    client_id: str
    key("client_id")
    request_id: str
    goal_id: str
    action_name: str


@dataclass
class CancelGoalResponse(IdlStruct, typename=f"{_MODULE}::CancelGoalResponse"):
    """The server's answer to a cancel request.

    Attributes:
        client_id: The client that asked; the key.
        request_id: The request answered.
        goal_id: The goal.
        action_name: Its action.
        return_code: A :class:`~actions.responses.CancelReturnCode`.
        message: A readable explanation.
        stamp_s: The server's time [s].
    """

    client_id: str
    key("client_id")
    request_id: str
    goal_id: str
    action_name: str
    return_code: int8
    message: str
    stamp_s: float64


@dataclass
class GoalFeedback(IdlStruct, typename=f"{_MODULE}::GoalFeedback"):
    """One feedback message of a running goal.

    Attributes:
        goal_id: The goal.
        action_name: Its action.
        feedback: The feedback message as JSON of its fields.
        stamp_s: The server's time [s] of the tick that produced it.
    """

    goal_id: str
    action_name: str
    feedback: str
    stamp_s: float64

    def serialize(self, buffer: Any = None, endianness: Any = None,
                  use_version_2: bool | None = None) -> bytes:
        """The XCDR1 message, byte for byte what cyclonedds' generic serialiser gives, in about
        a tenth of its time (feedback is written 50 times a second from the control loop's
        thread); any other request (a buffer, an endianness, XCDR2) goes the generic way."""
        if buffer is not None or endianness is not None or use_version_2:
            return super().serialize(buffer, endianness, use_version_2)
        out = bytearray(_XCDR1_LE)
        for text in (self.goal_id, self.action_name, self.feedback):
            _put_cdr_string(out, text)
        out += bytes(-(len(out) - len(_XCDR1_LE)) % 8)  # a float64 sits on 8 in XCDR1
        out += _FLOAT64.pack(self.stamp_s)
        return bytes(out)


@dataclass
class GoalStatusUpdate(IdlStruct, typename=f"{_MODULE}::GoalStatusUpdate"):
    """The latest status of one goal (ROS 2: an entry of ``GoalStatusArray``).

    Attributes:
        goal_id: The goal; the key.
        action_name: Its action.
        status: A :class:`~actions.goal_status.GoalStatus` value.
        stamp_s: The server's time [s] of the change.
    """

    goal_id: str
    key("goal_id")
    action_name: str
    status: int8
    stamp_s: float64


@dataclass
class GoalResult(IdlStruct, typename=f"{_MODULE}::GoalResult"):
    """A finished goal's terminal status and result, pushed by the server when it ends.

    Attributes:
        goal_id: The goal; the key.
        action_name: Its action.
        status: ``SUCCEEDED``, ``CANCELED`` or ``ABORTED`` (a GoalStatus value).
        result: The result message as JSON of its fields.
        stamp_s: The server's time [s] the goal ended.
    """

    goal_id: str
    key("goal_id")
    action_name: str
    status: int8
    result: str
    stamp_s: float64


@dataclass
class ServedActions(IdlStruct, typename=f"{_MODULE}::ServedActions"):
    """What one bridge serves, so that a client of an action nobody serves can say what is.

    Attributes:
        server_id: The bridge's id (UUID text); the key.
        action_names: The served action names, sorted.
        action_types: Their interfaces, in the same order.
    """

    server_id: str
    key("server_id")
    # `sequence[str]`, not `list[str]` (no XTypes type object for that); the ignores are for
    # type checkers without cyclonedds' mypy plugin.
    action_names: sequence[str] = field(default_factory=list)  # type: ignore[type-arg,assignment]
    action_types: sequence[str] = field(default_factory=list)  # type: ignore[type-arg,assignment]
