"""Goals, feedback and results on the wire: JSON of a message's fields, checked by its schema.

Why JSON of the fields rather than one IDL type per action: any ``.action`` travels over the
same seven wire types with nothing generated at run time; the schema that checks a message on
each end is the one the framework already has (the message classes made from the ``.action``
file: :meth:`~actions.messages.Message.validated_copy` and
:func:`~actions.message_fields.set_message_fields`), so a bad field is reported as it is for a
local goal (its path, what was received, what is valid). JSON keeps ``float64`` exact
(``repr`` round trip), carries nested messages (a ``Duration`` is ``{"sec": 1, "nanosec": 0}``)
and is what ``ros2 action send_goal`` takes. The cost: a few tens of microseconds a message,
and no typed interoperability with ROS 2 topics (not a goal here).
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

from actions.action_type import ActionType
from actions.message_fields import set_message_fields
from actions.messages import Message
from wbc.core.errors import ConfigurationError

#: The longest excerpt of a malformed payload quoted in an error [characters].
_QUOTE_CHARS = 120
#: Field values JSON writes as they are (no copy needed).
_FLAT_TYPES = frozenset((str, int, float, bool, type(None)))
_FIELD_NAMES: dict[type, tuple[str, ...]] = {}
#: ``json.dumps(..., separators=(",", ":"))`` without building an encoder per message.
_COMPACT_JSON = json.JSONEncoder(separators=(",", ":"))


def check_json_action(action_type: ActionType, *, what: str) -> ActionType:
    """``action_type`` if its goal, feedback and result can travel as JSON of their fields
    (dataclass subclasses of Message, as every class made from an ``.action`` file is).

    Args:
        action_type: The interface.
        what: What wants to send it, for errors (``"action 'high_five'"``).

    Raises:
        ConfigurationError: It is not an ActionType, or one of its classes is not such a class.
    """
    if not isinstance(action_type, ActionType):
        raise ConfigurationError(
            f"{what}: action_type must be an ActionType (e.g. HIGH_FIVE); received "
            f"{action_type!r}")
    for cls in (action_type.goal_type, action_type.feedback_type, action_type.result_type):
        if not (issubclass(cls, Message) and dataclasses.is_dataclass(cls)):
            raise ConfigurationError(
                f"{what} ({action_type.type_name}) cannot go over DDS: {cls.__name__} is not a "
                "dataclass subclass of Message")
    return action_type


def encode_message(message: Any, expected: type, *, what: str) -> str:
    """``message`` as compact JSON of its fields, after the schema check a local send makes.

    Args:
        message: A message of class ``expected``.
        expected: The action's goal, feedback or result class.
        what: What the message is, for errors (``"goal of 'high_five'"``).

    Raises:
        ConfigurationError: ``message`` is not an ``expected``, or a field has the wrong type
            or value (the message names the field, what was received and what is valid).
    """
    if not isinstance(message, expected) or not isinstance(message, Message):
        raise ConfigurationError(
            f"{what} must be a {expected.__name__}; received {message!r} "
            f"(type {type(message).__name__})")
    checked: Any = message.validated_copy()  # a dataclass (check_json_action)
    return _COMPACT_JSON.encode(_json_fields(checked))


def _json_fields(message: Any) -> dict[str, Any]:
    """A checked message's fields by name, in their order: a flat message's values as they are
    (``dataclasses.asdict``'s deep copy is most of the encoding's time, and feedback goes 50
    times a second from the control loop's thread), a nested one through ``asdict``."""
    cls = type(message)
    names = _FIELD_NAMES.get(cls)
    if names is None:
        names = _FIELD_NAMES[cls] = tuple(f.name for f in dataclasses.fields(message))
    fields = {name: getattr(message, name) for name in names}
    for value in fields.values():
        if type(value) not in _FLAT_TYPES:
            return dataclasses.asdict(message)
    return fields


def decode_message(text: str, cls: type, *, what: str) -> Any:
    """The message of class ``cls`` that ``text`` (JSON of its fields) describes, checked.

    Fields not named keep their defaults (as in ``ros2 action send_goal``).

    Args:
        text: The JSON text received.
        cls: The message class expected (a dataclass subclass of Message).
        what: What the message is, for errors.

    Raises:
        ConfigurationError: ``text`` is not JSON, not an object, names a field ``cls`` does
            not have, or a field has the wrong type or value; the message says which and
            quotes what was received.
    """
    try:
        values = json.loads(text)
    except json.JSONDecodeError as err:
        raise ConfigurationError(
            f"{what}: the payload is not JSON ({err}); received {_quote(text)}") from err
    try:
        return set_message_fields(cls(), values).validated_copy()
    except ConfigurationError as err:
        raise ConfigurationError(f"{what}: {err}") from err


def _quote(text: str) -> str:
    if len(text) <= _QUOTE_CHARS:
        return repr(text)
    return f"{text[:_QUOTE_CHARS]!r}... ({len(text)} characters)"
