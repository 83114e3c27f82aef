"""Parser of the ROS 2 ``.action`` / ``.msg`` interface format into field and constant lists."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

from wbc.core.errors import ConfigurationError

_INTEGER_TYPES = frozenset(
    {"byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
)
_FLOAT_TYPES = frozenset({"float32", "float64"})
_STRING_TYPES = frozenset({"string", "wstring"})
# type: a name, optionally package-qualified ("std_msgs/Header"), optionally a bounded string
# ("string<=8"), optionally an array ("[]", "[3]", "[<=3]").
_TYPE = re.compile(
    r"(?P<base>[A-Za-z][\w/]*)(?:<=\d+)?(?P<array>\[(?P<bound><=)?(?P<size>\d*)\])?$"
)
_NAME = re.compile(r"[A-Za-z]\w*$")


@dataclass(frozen=True)
class FieldSpec:
    """One field of a message definition.

    Attributes:
        type_name: The element type as written, without array suffix (``"float64"``,
            ``"JointTrajectoryPoint"``, ``"std_msgs/Header"``).
        name: The field name.
        is_array: Whether the field is an array (``T[]``, ``T[N]`` or ``T[<=N]``).
        array_size: ``N`` for ``T[N]`` / ``T[<=N]``, ``None`` for unbounded ``T[]`` or scalars.
        default: The default value as written after the name, or ``None``.
        line: The line of the file it is on, for error messages (not compared).
    """

    type_name: str
    name: str
    is_array: bool = False
    array_size: int | None = None
    default: str | None = None
    line: int | None = field(default=None, compare=False, repr=False)

    @property
    def base_type(self) -> str:
        """The type name without its package (``"std_msgs/Header"`` -> ``"Header"``)."""
        return self.type_name.rsplit("/", 1)[-1]


@dataclass(frozen=True)
class ConstantSpec:
    """One constant (``int32 SUCCESSFUL = 0``), its value parsed to ``int``, ``float``, ``bool``
    or ``str``."""

    type_name: str
    name: str
    value: int | float | bool | str
    line: int | None = field(default=None, compare=False, repr=False)


class MessageDefinition(NamedTuple):
    """The fields and constants of one message (or one section of an action), in file order."""

    fields: tuple[FieldSpec, ...]
    constants: tuple[ConstantSpec, ...]


class ActionDefinition(NamedTuple):
    """The three sections of an ``.action`` file; unpacks as ``goal, result, feedback``."""

    goal: MessageDefinition
    result: MessageDefinition
    feedback: MessageDefinition


def parse_action_file(path: str | Path) -> ActionDefinition:
    """Parse an ``.action`` file: goal, result and feedback sections separated by ``---``.

    Args:
        path: The ``.action`` file.

    Returns:
        The goal, result and feedback definitions (a 3-tuple).

    Raises:
        ConfigurationError: The file does not have exactly three sections or a line is not a
            field or constant; the message names the file and line.
    """
    path = Path(path)
    return parse_action_text(path.read_text(encoding="utf-8"), source=str(path))


def parse_action_text(text: str, *, source: str = "<string>") -> ActionDefinition:
    """Parse the text of an ``.action`` file; see :func:`parse_action_file`."""
    sections: list[list[tuple[int, str]]] = [[]]
    for number, line in enumerate(text.splitlines(), start=1):
        if line.strip() == "---":
            sections.append([])
        else:
            sections[-1].append((number, line))
    if len(sections) != 3:
        raise ConfigurationError(
            f"{source}: an action definition needs 3 sections (goal, result, feedback) "
            f"separated by '---' lines; found {len(sections)}"
        )
    goal, result, feedback = (_parse_lines(lines, source) for lines in sections)
    return ActionDefinition(goal, result, feedback)


def parse_message_text(text: str, *, source: str = "<string>") -> MessageDefinition:
    """Parse the text of a ``.msg`` file (one section: fields and constants)."""
    return _parse_lines(list(enumerate(text.splitlines(), start=1)), source)


def _parse_lines(lines: list[tuple[int, str]], source: str) -> MessageDefinition:
    fields: list[FieldSpec] = []
    constants: list[ConstantSpec] = []
    for number, raw in lines:
        where = f"{source}:{number}"
        code = raw.split("#", 1)[0].strip().replace("\t", " ")
        if not code:
            continue
        type_token, _, rest = code.partition(" ")
        match = _TYPE.match(type_token)
        if match is None or not rest.strip():
            raise ConfigurationError(
                f"{where}: expected '<type> <name> [default]' or '<type> <NAME>=<value>'; "
                f"received {raw.strip()!r}"
            )
        if "=" in rest:
            # Comments are part of a string constant's value, as in rosidl.
            value_text = raw.split("=", 1)[1].strip() if match["base"] in _STRING_TYPES else None
            constants.append(_parse_constant(match["base"], rest, value_text, where, number))
            continue
        name, _, default = rest.strip().partition(" ")
        if not _NAME.match(name):
            raise ConfigurationError(
                f"{where}: invalid field name {name!r} in line {raw.strip()!r}"
            )
        fields.append(
            FieldSpec(
                type_name=match["base"],
                name=name,
                is_array=match["array"] is not None,
                array_size=int(match["size"]) if match["size"] else None,
                default=default.strip() or None,
                line=number,
            )
        )
    return MessageDefinition(tuple(fields), tuple(constants))


def _parse_constant(
    type_name: str, rest: str, string_value: str | None, where: str, line: int
) -> ConstantSpec:
    name, _, value_text = (part.strip() for part in rest.partition("="))
    if not _NAME.match(name):
        raise ConfigurationError(f"{where}: invalid constant name {name!r}")
    if not is_scalar_type(type_name):
        raise ConfigurationError(
            f"{where}: constant {name} has type {type_name!r}; constants must be a "
            "number, bool or string"
        )
    try:
        value = parse_scalar(
            type_name, string_value if type_name in _STRING_TYPES and string_value is not None
            else value_text)
    except ValueError as err:
        raise ConfigurationError(
            f"{where}: constant {name} = {value_text!r} is not a valid {type_name}"
        ) from err
    return ConstantSpec(type_name=type_name, name=name, value=value, line=line)


def is_scalar_type(type_name: str) -> bool:
    """Whether ``type_name`` is a number, ``bool`` or string type (what a constant or a
    default value may have)."""
    return (type_name in _INTEGER_TYPES or type_name in _FLOAT_TYPES or type_name == "bool"
            or type_name in _STRING_TYPES)


def parse_scalar(type_name: str, text: str) -> int | float | bool | str:
    """A constant's or a default's value as written (``"-1"``, ``"2.0"``, ``"true"``,
    ``'"hi"'``), as the Python value of its type.

    Raises:
        ValueError: ``text`` is not a value of ``type_name``, or the type is not a scalar.
    """
    if type_name in _INTEGER_TYPES:
        return int(text, 0)
    if type_name in _FLOAT_TYPES:
        return float(text)
    if type_name == "bool":
        return _parse_bool(text)
    if type_name in _STRING_TYPES:
        return _unquote(text)
    raise ValueError(f"{type_name} is not a number, bool or string type")


def _parse_bool(text: str) -> bool:
    lowered = text.lower()
    if lowered in {"true", "1"}:
        return True
    if lowered in {"false", "0"}:
        return False
    raise ValueError(text)


def _unquote(text: str) -> str:
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    return text
