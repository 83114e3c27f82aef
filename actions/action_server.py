"""One named action on a robot: its type, behaviour factory and goal/cancel policies.

ROS 2 analogue: ``rclpy.action.ActionServer(node, action_type, name, execute_callback,
goal_callback=..., cancel_callback=...)``. Here the node is the :class:`ActionRunner` (which
owns the robot and runs one goal at a time) and the execute callback is a factory of
:class:`~actions.behaviour.Behaviour` objects stepped on the control tick.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any, Protocol

from actions.action_type import ActionType
from actions.behaviour import Behaviour
from actions.responses import GoalResponse, Rejection, RejectionCode
from wbc.core.errors import ConfigurationError
from wbc.core.validation import is_finite_real

logger = logging.getLogger(__name__)

#: A goal or cancel callback's answer.
Decision = GoalResponse | Rejection


class ServerRegistry(Protocol):
    """What a server registers with: the runner of its robot (ROS 2: the node)."""

    def add_server(self, server: ActionServer) -> None:
        """Register ``server``; raise if its name is taken."""
        ...


class ActionServer:
    """Serves one action name on a runner; registers itself with the runner on construction.

    Args:
        runner: The runner of the robot this action drives.
        action_type: The interface, e.g. ``HIGH_FIVE``.
        action_name: Name clients use, e.g. ``"high_five"``; unique per runner.
        behaviour_factory: Called with no arguments once per accepted goal; returns the
            :class:`Behaviour` that will run it (a class or a ``functools.partial`` works).
        goal_callback: ``goal_callback(goal)`` validates a goal before it is accepted. Return
            ``GoalResponse.ACCEPT``, ``GoalResponse.REJECT`` or a :class:`Rejection` with a
            code and a message (better: says what is wrong). Anything else, or an exception,
            rejects the goal with ``RejectionCode.CALLBACK_ERROR``. Default: accept all.
        cancel_callback: ``cancel_callback(goal_id, goal)`` decides on a cancel request, with
            the same vocabulary: ``GoalResponse.ACCEPT``, or ``GoalResponse.REJECT`` / a
            :class:`Rejection` (whose message is passed back; its code is not used, since
            ``CancelGoal`` has its own return codes) to refuse. Default: accept all.
        max_unwind_s: How long [s, simulated] a behaviour may take to finish after a cancel
            before the runner aborts it.

    Raises:
        ConfigurationError: An argument has the wrong type or value, or the name is taken.
    """

    def __init__(
        self,
        runner: ServerRegistry,
        action_type: ActionType,
        action_name: str,
        behaviour_factory: Callable[[], Behaviour[Any, Any, Any]],
        *,
        goal_callback: Callable[[Any], Decision] | None = None,
        cancel_callback: Callable[[str, Any], Decision] | None = None,
        max_unwind_s: float = 5.0,
    ) -> None:
        if not isinstance(action_type, ActionType):
            raise ConfigurationError(
                f"action_type must be an ActionType (e.g. HIGH_FIVE); received {action_type!r}"
            )
        if not isinstance(action_name, str) or not action_name:
            raise ConfigurationError(
                f"action_name must be a non-empty str; received {action_name!r}"
            )
        if not callable(behaviour_factory):
            raise ConfigurationError(
                f"behaviour_factory must be callable; received {behaviour_factory!r}"
            )
        for label, value in (
            ("goal_callback", goal_callback),
            ("cancel_callback", cancel_callback),
        ):
            if value is not None and not callable(value):
                raise ConfigurationError(f"{label} must be callable or None; received {value!r}")
        if not is_finite_real(max_unwind_s) or max_unwind_s <= 0:
            raise ConfigurationError(
                f"max_unwind_s must be a finite number of seconds > 0; received {max_unwind_s!r}"
            )
        self._action_type = action_type
        self._action_name = action_name
        self._behaviour_factory = behaviour_factory
        self._goal_callback = goal_callback
        self._cancel_callback = cancel_callback
        self._max_unwind_s = float(max_unwind_s)
        runner.add_server(self)

    @property
    def action_type(self) -> ActionType:
        """The interface served."""
        return self._action_type

    @property
    def action_name(self) -> str:
        """The name clients use."""
        return self._action_name

    @property
    def max_unwind_s(self) -> float:
        """Longest unwind [s, simulated] allowed after a cancel."""
        return self._max_unwind_s

    def evaluate_goal(self, goal: Any) -> Rejection | None:
        """Run the goal callback; ``None`` means accept. Never raises."""
        if self._goal_callback is None:
            return None
        return self._evaluate("goal callback", self._goal_callback, goal)

    def evaluate_cancel(self, goal_id: str, goal: Any) -> str | None:
        """Run the cancel callback; ``None`` means accept, else the refusal message."""
        if self._cancel_callback is None:
            return None
        refusal = self._evaluate("cancel callback", self._cancel_callback, goal_id, goal)
        return None if refusal is None else refusal.message

    def create_behaviour(self) -> Behaviour[Any, Any, Any]:
        """Make the behaviour for a newly accepted goal.

        Raises:
            ConfigurationError: The factory returned something that is not a Behaviour.
            Exception: Whatever the factory raised.
        """
        behaviour = self._behaviour_factory()
        if not isinstance(behaviour, Behaviour):
            raise ConfigurationError(
                f"behaviour factory of '{self._action_name}' returned {behaviour!r}; "
                "expected a Behaviour instance"
            )
        return behaviour

    def _evaluate(self, what: str, callback: Callable[..., Any], *args: Any) -> Rejection | None:
        where = f"{what} of '{self._action_name}'"
        try:
            decision = callback(*args)
        except Exception as err:
            logger.exception("%s raised", where)
            return Rejection(
                RejectionCode.CALLBACK_ERROR, f"{where} raised {type(err).__name__}: {err}"
            )
        if decision is GoalResponse.ACCEPT:
            return None
        if decision is GoalResponse.REJECT:
            return Rejection(RejectionCode.REJECTED, f"rejected by the {where}")
        if isinstance(decision, Rejection):
            return decision
        return Rejection(
            RejectionCode.CALLBACK_ERROR,
            f"{where} returned {decision!r}; expected GoalResponse.ACCEPT, "
            "GoalResponse.REJECT or a Rejection",
        )
