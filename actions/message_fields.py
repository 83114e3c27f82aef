"""Fill a message from a mapping, as ``rosidl_runtime_py.set_message_fields`` does for ROS 2.

The mapping comes from YAML or JSON (``go2-wbc send-goal high_five "{target_height: 0.4}"``,
as ``ros2 action send_goal`` takes it): nested messages are mappings, arrays of messages are
lists of mappings, and a ``Duration`` or ``Time`` is ``{sec: 1, nanosec: 0}`` or a number of
seconds.
"""

from __future__ import annotations

import typing
from collections.abc import Mapping
from typing import Any, TypeVar

from actions.errors import UnknownFieldError
from actions.messages import Message, field_types, no_such_field
from wbc.core.errors import ConfigurationError

M = TypeVar("M", bound=Message)


def set_message_fields(message: M, values: Any, *, where: str | None = None) -> M:
    """Set the fields of ``message`` named in ``values``, nested messages included.

    A nested message given as a mapping is built anew from its defaults and that mapping (as
    in ROS 2); fields not named keep their values. Only the names are checked here; the
    types are checked by :meth:`Message.validated_copy`, or when the message is sent, so
    that a type error names the field's whole path.

    Args:
        message: The message to fill, e.g. ``HighFiveGoal()``.
        values: A mapping of field names to values.
        where: The message's path in error messages (default: its class name).

    Returns:
        ``message``, filled.

    Raises:
        UnknownFieldError: A key is not a field; the message names its path and lists the
            fields of that message.
        ConfigurationError: ``values`` (or a nested one) is not a mapping.
    """
    cls = type(message)
    where = cls.__name__ if where is None else where
    if not isinstance(values, Mapping):
        raise ConfigurationError(
            f"{where} must be a mapping of field names to values (e.g. "
            f"{{{next(iter(field_types(cls)), 'field')}: ...}}); received {values!r} "
            f"(type {type(values).__name__})"
        )
    types = field_types(cls)
    for key, value in values.items():
        if key not in types:
            raise UnknownFieldError(no_such_field(cls, key, where))
        setattr(message, key, _field_value(types[key], value, f"{where}.{key}"))
    return message


def _field_value(hint: Any, value: Any, where: str) -> Any:
    """``value`` with the mappings in it turned into messages of the field's types."""
    if _is_message_class(hint) and isinstance(value, Mapping):
        return set_message_fields(hint(), value, where=where)
    if typing.get_origin(hint) is list and isinstance(value, list):
        (item_hint,) = typing.get_args(hint)
        return [_field_value(item_hint, item, f"{where}[{i}]") for i, item in enumerate(value)]
    return value


def _is_message_class(hint: Any) -> bool:
    return isinstance(hint, type) and issubclass(hint, Message)
