"""One schema per message: a section of an ``.action`` file, checked against a class or made one.

The ``.action`` files define the messages. A message class is either declared in Python (a
``@dataclass(slots=True)`` subclass of :class:`~actions.messages.Message`, so that type
checkers and editors see its fields) and checked against its section once, at import, by
:func:`check_message_class`; or built from its section by :func:`message_class`. Both follow the
same rules (:func:`field_type`, :func:`default_value`), so a declared class and a built one of
the same section hold the same fields, types and defaults:

- ``float32``, ``float64`` -> ``float``; ``byte``, ``char``, ``int8`` ... ``uint64`` -> ``int``;
  ``bool`` -> ``bool``; ``string``, ``wstring`` -> ``str``; ``duration``, ``time`` (and
  ``builtin_interfaces/Duration``, ``/Time``) -> :class:`~actions.messages.Duration`,
  :class:`~actions.messages.Time`; any other name -> the message class of that name (the
  package part, as in ``std_msgs/Header``, is not compared);
- an array (``T[]``, ``T[N]``, ``T[<=N]``) -> ``list[T]``, its size not enforced;
- a field's default is the one the file gives after its name, else 0, ``False``, empty, or the
  nested message built empty.
"""

from __future__ import annotations

import ast
import dataclasses
import functools
import typing
from collections.abc import Mapping
from types import GenericAlias
from typing import Any, ClassVar

from actions.action_definition import FieldSpec, MessageDefinition, is_scalar_type, parse_scalar
from actions.errors import InterfaceMismatchError
from actions.messages import Duration, Message, Time, field_types
from wbc.core.errors import ConfigurationError

#: The Python type of a field of each ROS 2 primitive type (builtin_interfaces' two included).
PRIMITIVE_TYPES: dict[str, type] = {
    **dict.fromkeys(("float32", "float64"), float),
    **dict.fromkeys(
        ("byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"),
        int,
    ),
    "bool": bool,
    "string": str,
    "wstring": str,
    "duration": Duration,
    "time": Time,
    "builtin_interfaces/Duration": Duration,
    "builtin_interfaces/Time": Time,
}
# A field may not take the name of a method every message has.
_RESERVED = frozenset(name for name in dir(Message) if not name.startswith("_"))


def field_type(spec: FieldSpec, types: Mapping[str, type[Message]], *, source: str) -> Any:
    """The Python type of a field: ``float``, ``int``, ``bool``, ``str``, a message class, or
    ``list[...]`` of one of these.

    Args:
        spec: The field, as parsed.
        types: Message classes a field may name, by class name (``"JointTrajectory"``).
        source: The file, for error messages.

    Raises:
        ConfigurationError: The type is neither a primitive nor in ``types``; the message
            names the file, line and field and lists the known types.
    """
    element = PRIMITIVE_TYPES.get(spec.type_name) or types.get(spec.base_type)
    if element is None:
        known = ", ".join([*PRIMITIVE_TYPES, *sorted(types)])
        raise ConfigurationError(
            f"{_at(source, spec)}: field {spec.name!r} has type {spec.type_name!r}, which is "
            f"neither a primitive type nor a message class given in types; known types: {known}"
        )
    return GenericAlias(list, (element,)) if spec.is_array else element  # list[element]


def default_value(spec: FieldSpec, element: type, *, source: str) -> Any:
    """What the field holds in a message built empty: the default the file gives, else 0,
    ``False``, ``""``, ``[]`` or the nested message built empty.

    Args:
        spec: The field, as parsed.
        element: The Python type of the field, or of its elements for an array.
        source: The file, for error messages.

    Raises:
        ConfigurationError: The default is not a value of the field's type, or the field's
            type cannot have one (a message); the message names the file, line and field.
    """
    if spec.default is None:
        return [] if spec.is_array else element()
    if not is_scalar_type(spec.type_name):
        raise ConfigurationError(
            f"{_at(source, spec)}: field {spec.name!r} of type {spec.type_name} cannot have a "
            f"default (only numbers, bool and strings can); received {spec.default!r}"
        )
    try:
        if not spec.is_array:
            return parse_scalar(spec.type_name, spec.default)
        values = ast.literal_eval(spec.default)  # written as in ROS 2: [1.0, 2.0]
        if not isinstance(values, list | tuple):
            raise ValueError(spec.default)
        return [_array_item(element, value) for value in values]
    except (ValueError, SyntaxError) as err:
        array = "[]" if spec.is_array else ""
        raise ConfigurationError(
            f"{_at(source, spec)}: the default {spec.default!r} of field {spec.name!r} is not a "
            f"valid {spec.type_name}{array}"
        ) from err


def message_class(
    name: str,
    definition: MessageDefinition,
    *,
    types: Mapping[str, type[Message]] | None = None,
    source: str = "<string>",
    doc: str | None = None,
) -> type[Message]:
    """A message class built from ``definition``: a ``@dataclass(slots=True)`` subclass of
    :class:`~actions.messages.Message`, its fields, defaults and constants the file's.

    Args:
        name: The class name, e.g. ``"WaveGoal"``.
        definition: The section of the ``.action`` file.
        types: Message classes its fields may name, by class name.
        source: The file, for error messages.
        doc: The class docstring (default: says where it was built from).

    Raises:
        ConfigurationError: A field's type is unknown, its default invalid, or its name is
            one of a message's methods.
    """
    types = {} if types is None else types
    fields: list[tuple[str, Any, Any]] = []
    for spec in definition.fields:
        if spec.name in _RESERVED:
            raise ConfigurationError(
                f"{_at(source, spec)}: field {spec.name!r} has the name of a method of every "
                f"message; reserved names: {', '.join(sorted(_RESERVED))}"
            )
        hint = field_type(spec, types, source=source)
        element = typing.get_args(hint)[0] if spec.is_array else hint
        default = default_value(spec, element, source=source)
        if isinstance(default, list):
            value = dataclasses.field(default_factory=functools.partial(list, default))
        elif isinstance(default, Message):
            value = dataclasses.field(default_factory=element)
        else:
            value = dataclasses.field(default=default)
        fields.append((spec.name, hint, value))
    for constant in definition.constants:
        fields.append((constant.name, ClassVar[type(constant.value)], constant.value))
    cls = dataclasses.make_dataclass(name, fields, bases=(Message,), slots=True)
    cls.__module__ = __name__
    cls.__doc__ = doc if doc is not None else f"{name}, built from {source}."
    return cls


def check_message_class(
    cls: Any, definition: MessageDefinition, *, source: str, section: str
) -> None:
    """Raise unless ``cls`` declares what ``definition`` says: the same fields in the same
    order, each of the file's type and default, and the same constants.

    Args:
        cls: The declared class, e.g. ``HighFiveGoal``.
        definition: Its section of the ``.action`` file.
        source: The file, for error messages.
        section: ``"goal"``, ``"result"`` or ``"feedback"``, for error messages.

    Raises:
        InterfaceMismatchError: They differ; the message names the class, the field or
            constant, what the file says (and on which line) and what the class declares.
    """
    name = cls.__name__ if isinstance(cls, type) else repr(cls)
    where = f"{name} does not match {source} ({section})"
    if not (isinstance(cls, type) and issubclass(cls, Message) and dataclasses.is_dataclass(cls)):
        raise InterfaceMismatchError(
            f"{where}: expected a @dataclass(slots=True) subclass of Message; received {cls!r}"
        )
    declared = field_types(cls)
    in_file = [spec.name for spec in definition.fields]
    listing = f"the file's fields: {_names(in_file)}; the class's: {_names(declared)}"
    for spec in definition.fields:
        if spec.name not in declared:
            raise InterfaceMismatchError(
                f"{where}: field {spec.name!r} ({_line(spec)}: {_written(spec)}) is missing "
                f"from the class; {listing}"
            )
    for field_name in declared:
        if field_name not in in_file:
            raise InterfaceMismatchError(
                f"{where}: field {field_name!r} of the class is not in the file; {listing}"
            )
    if list(declared) != in_file:
        raise InterfaceMismatchError(f"{where}: the fields are in another order; {listing}")
    try:
        empty = cls()
    except Exception as err:
        raise InterfaceMismatchError(
            f"{where}: the class cannot be built empty ({type(err).__name__}: {err}); every "
            "field needs a default: the file's, else 0, False, empty or the message built empty"
        ) from err
    for spec in definition.fields:
        _check_field(spec, declared[spec.name], getattr(empty, spec.name), where, source)
    _check_constants(cls, definition, where)


def _check_field(spec: FieldSpec, hint: Any, value: Any, where: str, source: str) -> None:
    """Raise unless a declared field has the type and default ``spec`` gives it."""
    is_list = typing.get_origin(hint) is list
    element = typing.get_args(hint)[0] if is_list else hint
    primitive = PRIMITIVE_TYPES.get(spec.type_name)
    if primitive is not None:
        same_element, expected = element is primitive, primitive.__name__
    else:
        same_element = (isinstance(element, type) and issubclass(element, Message)
                        and element.__name__ == spec.base_type)
        expected = f"the message {spec.base_type}"
    if is_list != spec.is_array or not same_element:
        expected = f"a list of {expected}" if spec.is_array else expected
        raise InterfaceMismatchError(
            f"{where}: field {spec.name!r} is declared {_type_text(hint)}; the file says "
            f"{_written(spec)} ({_line(spec)}), which is {expected}"
        )
    default = default_value(spec, element, source=source)
    if value != default or type(value) is not type(default):
        said = (f"the default {spec.default}" if spec.default is not None
                else f"no default, so {default!r}")
        raise InterfaceMismatchError(
            f"{where}: field {spec.name!r} defaults to {value!r}; the file gives {said} "
            f"({_line(spec)}: {_written(spec)})"
        )


def _check_constants(cls: type, definition: MessageDefinition, where: str) -> None:
    """Raise unless the class's ``ClassVar`` constants are the file's, with the same values."""
    hints = typing.get_type_hints(cls)
    declared = {name: getattr(cls, name) for name, hint in hints.items()
                if typing.get_origin(hint) is ClassVar}
    for constant in definition.constants:
        if constant.name not in declared:
            raise InterfaceMismatchError(
                f"{where}: constant {constant.name!r} (line {constant.line}: {constant.type_name} "
                f"{constant.name}={constant.value!r}) is missing from the class"
            )
        value = declared.pop(constant.name)
        if value != constant.value or type(value) is not type(constant.value):
            raise InterfaceMismatchError(
                f"{where}: constant {constant.name!r} is {value!r} in the class; the file says "
                f"{constant.value!r} (line {constant.line})"
            )
    if declared:
        extra = ", ".join(declared)
        raise InterfaceMismatchError(f"{where}: the class has constants not in the file: {extra}")


def _array_item(element: type, value: Any) -> Any:
    """One element of an array default, as the element type (an int is a float's too)."""
    if element is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if type(value) is not element:
        raise ValueError(value)
    return value


def _at(source: str, spec: FieldSpec) -> str:
    return source if spec.line is None else f"{source}:{spec.line}"


def _line(spec: FieldSpec) -> str:
    return "line ?" if spec.line is None else f"line {spec.line}"


def _written(spec: FieldSpec) -> str:
    """The field as the file writes it: ``float32 target_height``."""
    array = "" if not spec.is_array else f"[{'' if spec.array_size is None else spec.array_size}]"
    default = "" if spec.default is None else f" {spec.default}"
    return f"{spec.type_name}{array} {spec.name}{default}"


def _type_text(hint: Any) -> str:
    """``float``, ``JointTrajectory``, ``list[JointTrajectoryPoint]``: a type as declared."""
    if typing.get_origin(hint) is list:
        return f"list[{_type_text(typing.get_args(hint)[0])}]"
    return getattr(hint, "__name__", repr(hint))


def _names(names: Any) -> str:
    return ", ".join(names) or "(none)"
