"""The action framework's ground errors, in the library's :class:`~wbc.core.errors.WbcError` family.

This module imports nothing else of the framework, so every module may raise these. The errors
that carry a goal handle or a rejection live with the class that raises them, above the types
they hold: :class:`~actions.client_goal_handle.GoalRejectedError` (in
``actions.client_goal_handle``), :class:`~actions.action_client.ActionTimeoutError` and
:class:`~actions.action_client.RunnerStalledError` (in ``actions.action_client``).
"""

from __future__ import annotations

from wbc.core.errors import ConfigurationError, WbcError


class UnknownFieldError(ConfigurationError, AttributeError):
    """A message has no field of that name (a misspelt field); the message lists its fields.

    An ``AttributeError`` too, as setting an unknown attribute on a ROS 2 message is.
    """


class InterfaceMismatchError(ConfigurationError):
    """A message class declared in Python does not match the ``.action`` file that defines it.

    Raised at import by :meth:`~actions.action_type.ActionType.from_file`; the message names
    the class, the field (or constant), what the file says and what the class declares.
    """


class IllegalTransitionError(WbcError):
    """A goal status change that the action state machine does not allow."""


class ActionUsageError(WbcError, RuntimeError):
    """An action API was called where it cannot work, e.g. a blocking wait in a tick callback."""
