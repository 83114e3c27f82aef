"""Converts between the library's messages (``actions.messages.Message`` dataclasses) and the
rosidl-generated messages of ``go2_interfaces``, ``control_msgs`` and their dependencies, by
field name (the two are generated from the same definitions, so the names match).
"""

from __future__ import annotations

import array
import dataclasses
import importlib
from collections.abc import Mapping
from typing import Any

from actions.message_fields import set_message_fields
from actions.messages import Message
from wbc.core.errors import ConfigurationError


def is_ros_message(value: Any) -> bool:
    """Whether ``value`` is a rosidl-generated message instance."""
    return hasattr(type(value), "get_fields_and_field_types")


def ros_to_dict(message: Any) -> dict[str, Any]:
    """A rosidl message as nested plain values (dicts, lists, numbers, strings)."""
    out: dict[str, Any] = {}
    for name in type(message).get_fields_and_field_types():
        out[name] = _plain(getattr(message, name))
    return out


def _plain(value: Any) -> Any:
    if is_ros_message(value):
        return ros_to_dict(value)
    if isinstance(value, array.array):
        return value.tolist()
    if isinstance(value, list | tuple):
        return [_plain(item) for item in value]
    if hasattr(value, "tolist"):  # numpy arrays of fixed-size fields
        return value.tolist()
    return value


def to_library(ros_message: Any, message_type: type[Message]) -> Message:
    """The library's message of ``message_type`` holding ``ros_message``'s fields, validated.

    Raises:
        ConfigurationError: A field the library's message lacks, or a value it refuses (the
            message names the field).
    """
    return set_message_fields(message_type(), ros_to_dict(ros_message)).validated_copy()


def _message_class(type_text: str) -> type[Any]:
    """The rosidl class of a field type such as ``trajectory_msgs/JointTrajectoryPoint``."""
    package, _, name = type_text.partition("/")
    return getattr(importlib.import_module(f"{package}.msg"), name)


def fill_ros(ros_message: Any, values: Mapping[str, Any], *, where: str = "") -> Any:
    """Set ``ros_message``'s fields from ``values`` (nested dicts and lists), in place.

    Keys the ROS message lacks are refused; ROS fields not given keep their defaults.

    Raises:
        ConfigurationError: An unknown field (named with its path).
    """
    cls = type(ros_message)
    types = cls.get_fields_and_field_types()
    where = where or cls.__name__
    for key, value in values.items():
        if key not in types:
            raise ConfigurationError(
                f"{where}.{key}: not a field of {cls.__name__}; its fields: "
                f"{', '.join(types)}")
        kind = types[key]
        current = getattr(ros_message, key)
        if is_ros_message(current) and isinstance(value, Mapping):
            fill_ros(current, value, where=f"{where}.{key}")
        elif kind.startswith("sequence<") and "/" in kind:
            item_cls = _message_class(kind[len("sequence<"):].split(",")[0].rstrip(">"))
            setattr(ros_message, key, [
                fill_ros(item_cls(), item, where=f"{where}.{key}[{i}]")
                for i, item in enumerate(value)])
        else:
            setattr(ros_message, key, value)
    return ros_message


def to_ros(message: Message, ros_type: type[Any]) -> Any:
    """A new ``ros_type`` message holding the library's ``message``'s fields."""
    return fill_ros(ros_type(), dataclasses.asdict(message))
