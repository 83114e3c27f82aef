"""An action's name tied to its goal, result and feedback types, made from its ``.action`` file.

The ROS 2 analogue is the generated action class (``control_msgs.action.FollowJointTrajectory``
with its ``Goal``, ``Result`` and ``Feedback``): ``FOLLOW_JOINT_TRAJECTORY.Goal(...)`` reads the
same. The ``.action`` file is the one definition of an action's messages:
:meth:`ActionType.from_file` checks the classes declared for it against the file, or builds
them from it (:mod:`actions.message_schema`). Adding an action takes its ``.action`` file, its
behaviour and one line that serves it::

    ActionServer(runner, ActionType.from_file(path, package="my_interfaces"), "wave", Wave)
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import KW_ONLY, dataclass
from pathlib import Path
from typing import Any, Generic, TypeVar, overload

from actions.action_definition import parse_action_file
from actions.message_schema import check_message_class, message_class
from actions.messages import Message, field_types
from wbc.core.errors import ConfigurationError, UnknownNameError

#: Where the library's ``.action`` files are (packaged with it).
INTERFACES_DIR = Path(__file__).resolve().parent / "interfaces"
#: A ROS 2 package name (REP 144): lower case letters, digits and underscores.
_PACKAGE_NAME = re.compile(r"[a-z][a-z0-9_]*$")
#: A ROS 2 interface name: CamelCase letters and digits.
_INTERFACE_NAME = re.compile(r"[A-Z][A-Za-z0-9]*$")
_SECTIONS = ("Goal", "Result", "Feedback")

#: An action's goal, result and feedback classes, for type checkers: ``HIGH_FIVE.Goal`` is
#: ``type[HighFiveGoal]``, so a misspelt field is a type error.
GoalT = TypeVar("GoalT")
ResultT = TypeVar("ResultT")
FeedbackT = TypeVar("FeedbackT")
_G = TypeVar("_G")
_R = TypeVar("_R")
_F = TypeVar("_F")


@dataclass(frozen=True)
class ActionType(Generic[GoalT, ResultT, FeedbackT]):
    """An action interface: its name and message types.

    Made from its ``.action`` file with :meth:`from_file`, which keeps the classes in step
    with the file.

    Attributes:
        name: Interface name, also the ``.action`` file's stem (``"HighFive"``).
        goal_type: Class of the goal message.
        result_type: Class of the result message.
        feedback_type: Class of the feedback message.
        package: The ROS 2 package that defines the interface (``"control_msgs"`` for
            FollowJointTrajectory); :attr:`type_name` is the full name.
        failure_result: Builds a failure result from a message; see :meth:`failure`.
        interface_path: The ``.action`` file that defines the interface, if any.
    """

    name: str
    goal_type: type[GoalT]
    result_type: type[ResultT]
    feedback_type: type[FeedbackT]
    _: KW_ONLY
    package: str
    failure_result: Callable[[str], Any] | None = None
    interface_path: Path | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _INTERFACE_NAME.match(self.name):
            raise ConfigurationError(
                f"ActionType name must be an interface name in CamelCase (letters and digits, "
                f"e.g. 'HighFive'); received {self.name!r}")
        if not isinstance(self.package, str) or not _PACKAGE_NAME.match(self.package):
            raise ConfigurationError(
                f"ActionType {self.name!r}: package must be a ROS 2 package name (lower case "
                f"letters, digits and underscores, e.g. 'control_msgs'); received "
                f"{self.package!r}")
        for attribute in ("goal_type", "result_type", "feedback_type"):
            value = getattr(self, attribute)
            if not isinstance(value, type):
                raise ConfigurationError(
                    f"ActionType {self.name!r}: {attribute} must be a class; received {value!r}"
                )
        if self.failure_result is None:
            if not issubclass(self.result_type, Message):
                raise ConfigurationError(
                    f"ActionType {self.name!r}: failure_result must be given, since the result "
                    f"type {self.result_type.__name__} is not a Message to fill by default")
        elif not callable(self.failure_result):
            raise ConfigurationError(
                f"ActionType {self.name!r}: failure_result must be callable or None; "
                f"received {self.failure_result!r}"
            )

    @overload
    @classmethod
    def from_file(
        cls, path: str | Path, *, package: str, goal_type: type[_G], result_type: type[_R],
        feedback_type: type[_F], failure_result: Callable[[str], Any] | None = None,
        types: Iterable[type[Message]] = (),
    ) -> ActionType[_G, _R, _F]: ...

    @overload
    @classmethod
    def from_file(
        cls, path: str | Path, *, package: str, goal_type: None = None,
        result_type: None = None, feedback_type: None = None,
        failure_result: Callable[[str], Any] | None = None,
        types: Iterable[type[Message]] = (),
    ) -> ActionType[Any, Any, Any]: ...

    @classmethod
    def from_file(
        cls,
        path: str | Path,
        *,
        package: str,
        goal_type: type | None = None,
        result_type: type | None = None,
        feedback_type: type | None = None,
        failure_result: Callable[[str], Any] | None = None,
        types: Iterable[type[Message]] = (),
    ) -> ActionType[Any, Any, Any]:
        """The action defined by the ``.action`` file at ``path``, named after the file.

        A message class given is checked against its section of the file (so that classes
        declared in Python for type checkers cannot drift from the file); one not given is
        built from its section, named ``<Name>Goal``, ``<Name>Result``, ``<Name>Feedback``.

        Args:
            path: The ``.action`` file, e.g. ``INTERFACES_DIR / "HighFive.action"``.
            package: The ROS 2 package of the interface, e.g. ``"go2_interfaces"``.
            goal_type, result_type, feedback_type: Declared classes to check, or ``None`` to
                build them.
            failure_result: As in :class:`ActionType`.
            types: Message classes the file's fields may name (``JointTrajectory``), for the
                classes built; ``Duration`` and ``Time`` are always known.

        Raises:
            ConfigurationError: The file cannot be read or parsed, names an unknown type, or
                its name is not an interface name (the message names the file and line).
            InterfaceMismatchError: A class given differs from the file; the message names
                the class, the field, what the file says and what the class declares.
        """
        path = Path(path)
        name = path.stem
        if not _INTERFACE_NAME.match(name) or path.suffix != ".action":
            raise ConfigurationError(
                f"{path}: an action file is named after its interface in CamelCase with the "
                f"suffix .action (e.g. HighFive.action); received {path.name!r}")
        try:
            definition = parse_action_file(path)
        except OSError as err:
            raise ConfigurationError(f"{path}: cannot read the action file: {err}") from err
        known = {message.__name__: message for message in types}
        classes: list[type[Any]] = []
        for section, declared, spec in zip(_SECTIONS, (goal_type, result_type, feedback_type),
                                           definition, strict=True):
            if declared is None:
                classes.append(message_class(
                    f"{name}{section}", spec, types=known, source=str(path),
                    doc=f"{section} of {package}/action/{name}, built from {path.name}."))
            else:
                check_message_class(declared, spec, source=str(path), section=section.lower())
                classes.append(declared)
        goal, result, feedback = classes
        return cls(name, goal, result, feedback, package=package,
                   failure_result=failure_result, interface_path=path)

    @property
    def Goal(self) -> type[GoalT]:  # rclpy spelling: FollowJointTrajectory.Goal
        """The goal class, as in ``FOLLOW_JOINT_TRAJECTORY.Goal(trajectory=...)``."""
        return self.goal_type

    @property
    def Result(self) -> type[ResultT]:
        """The result class."""
        return self.result_type

    @property
    def Feedback(self) -> type[FeedbackT]:
        """The feedback class."""
        return self.feedback_type

    @property
    def type_name(self) -> str:
        """The full name, as ``ros2 action list -t`` prints it: ``control_msgs/action/...``."""
        return f"{self.package}/action/{self.name}"

    def is_named(self, text: str) -> bool:
        """Whether ``text`` names this interface in a form ROS 2 takes: ``HighFive``,
        ``go2_interfaces/HighFive`` or ``go2_interfaces/action/HighFive``."""
        return text in (self.name, f"{self.package}/{self.name}", self.type_name)

    def failure(self, message: str) -> Any:
        """A result for a goal the framework ends with ``message``.

        The runner uses it only when a behaviour's own ``abort_result`` raises or returns the
        wrong type, so that every goal still ends with a result of :attr:`result_type`. It is
        ``failure_result(message)`` if given, else the result built empty with ``message`` in
        its first string field (``message``, ``error_string``), if it has one.
        """
        if self.failure_result is not None:
            return self.failure_result(message)
        result = self.result_type()
        text = next((name for name, hint in field_types(self.result_type).items()
                     if hint is str), None)
        if text is not None:
            setattr(result, text, message)
        return result


def action_type_named(text: str, types: Iterable[ActionType]) -> ActionType:
    """The action type ``text`` names among ``types``: ``HighFive``,
    ``go2_interfaces/HighFive`` or ``go2_interfaces/action/HighFive`` (as ``ros2 action
    send_goal`` and ``ros2 interface show`` take them).

    Args:
        text: The name.
        types: The types to choose from, e.g. ``ACTION_TYPES.values()`` of
            :mod:`actions.go2.go2_interfaces`.

    Raises:
        UnknownNameError: No such type; the message lists the valid full names (and the
            right package when only the package is wrong).
    """
    candidates = sorted(types, key=lambda t: t.type_name)
    for action_type in candidates:
        if action_type.is_named(text):
            return action_type
    last = text.rsplit("/", 1)[-1]
    same_name = [t.type_name for t in candidates if t.name == last]
    hint = f" ({last} is {' or '.join(same_name)})" if same_name else ""
    if not candidates:
        raise UnknownNameError(f"unknown action type {text!r}; there are no action types")
    valid = ", ".join(t.type_name for t in candidates)
    raise UnknownNameError(f"unknown action type {text!r}{hint}; valid action types: {valid} "
                           f"(or the last part alone, e.g. {candidates[-1].name})")


def action_types_in(
    directory: str | Path,
    *,
    package: str,
    known: Iterable[ActionType] = (),
    types: Iterable[type[Message]] = (),
) -> dict[str, ActionType]:
    """Every action defined by an ``.action`` file in ``directory``, by name, in file order.

    Args:
        directory: Where the files are, e.g. :data:`INTERFACES_DIR`.
        package: The package of the ones built here.
        known: Action types already made from files there (with declared classes, or of
            another package); they are used as they are.
        types: Message classes the files' fields may name, for the ones built here.

    Raises:
        ConfigurationError: A known type's file is not in ``directory``, or a file is invalid.
    """
    directory = Path(directory).resolve()
    by_name = {action.name: action for action in known}
    for action in by_name.values():
        path = action.interface_path
        if path is None or path.resolve().parent != directory:
            raise ConfigurationError(
                f"action type {action.name!r} is defined by {action.interface_path}, not by a "
                f"file in {directory}")
    types = tuple(types)
    return {path.stem: by_name.get(path.stem) or ActionType.from_file(
        path, package=package, types=types) for path in sorted(directory.glob("*.action"))}
