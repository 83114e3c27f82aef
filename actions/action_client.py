"""Sends goals to one action of a runner and waits for them (ROS 2: ``rclpy.action.ActionClient``).

Names follow rclpy: ``send_goal_async`` returns a future of a :class:`ClientGoalHandle`, whose
``get_result_async`` and ``cancel_goal_async`` return futures too. ``send_goal_and_wait`` is
the blocking shortcut, usable with or without a thread that ticks the runner.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeoutError
from typing import TYPE_CHECKING, Any, Generic, Protocol, TypeVar, overload

from actions.action_runner import ActionRunner
from actions.action_type import ActionType
from actions.client_goal_handle import ClientGoalHandle, GoalRejectedError
from actions.errors import ActionUsageError
from wbc.core.errors import ConfigurationError, WbcError
from wbc.core.validation import is_finite_real

if TYPE_CHECKING:
    from actions.responses import CancelResponse, FeedbackMessage, WrappedResult

T = TypeVar("T")
#: The action's goal, result and feedback classes (``HighFiveGoal``, ...), from its
#: :class:`ActionType`: a client made with the interface is typed by it.
GoalT = TypeVar("GoalT")
ResultT = TypeVar("ResultT")
FeedbackT = TypeVar("FeedbackT")


class HoldsRunner(Protocol):
    """What holds a runner as ``.runner`` (a ``ControlLoop``: rclpy's node)."""

    @property
    def runner(self) -> ActionRunner: ...


class ActionTimeoutError(WbcError, TimeoutError):
    """A blocking action call did not finish in time. The goal is NOT cancelled.

    Attributes:
        goal_handle: The handle of the accepted goal, or ``None`` when the goal request itself
            had not been processed yet (then use :attr:`goal_handle_future`).
        goal_handle_future: Resolves to the goal's handle once a tick processes the request.
    """

    def __init__(
        self,
        message: str,
        *,
        goal_handle: ClientGoalHandle | None = None,
        goal_handle_future: Future[ClientGoalHandle] | None = None,
    ) -> None:
        super().__init__(message)
        self.goal_handle = goal_handle
        self.goal_handle_future = goal_handle_future


class RunnerStalledError(ActionTimeoutError):
    """Nothing ticks the runner: no thread calls ``tick`` and no spin hook can drive it."""


class ActionClient(Generic[GoalT, ResultT, FeedbackT]):
    """Client of one named action on a runner. Every method may be called from any thread.

    Made as ``ActionClient(runner, "high_five")``, or in rclpy's order with the interface,
    ``ActionClient(runner, HIGH_FIVE, "high_five")`` (rclpy: ``ActionClient(node, HighFive,
    "high_five")``), which also checks that the server has that interface. In place of the
    runner, anything that holds one as ``.runner`` will do: a ``ControlLoop``, which plays the
    part of rclpy's node (``ActionClient(loop, HIGH_FIVE, "high_five")``).

    Args:
        runner: The runner serving the action, or an object with one as ``.runner``.
        action: The server's name, e.g. ``"high_five"``; or its :class:`ActionType` when
            ``action_name`` follows.
        action_name: The server's name, when ``action`` is the interface.

    Raises:
        UnknownNameError: The runner has no server of that name; lists the served names.
        ConfigurationError: The interface given is not the one the server serves, or the
            arguments are of the wrong types.
    """

    @overload
    def __init__(self: ActionClient[GoalT, ResultT, FeedbackT], runner: ActionRunner | HoldsRunner,
                 action: ActionType[GoalT, ResultT, FeedbackT], action_name: str) -> None: ...

    @overload
    def __init__(self: ActionClient[Any, Any, Any], runner: ActionRunner | HoldsRunner,
                 action: str, action_name: None = None) -> None: ...

    def __init__(self, runner: ActionRunner | HoldsRunner,
                 action: ActionType[Any, Any, Any] | str, action_name: str | None = None
                 ) -> None:
        if action_name is None:
            if not isinstance(action, str):
                raise ConfigurationError(
                    f"ActionClient needs the action's name: ActionClient(runner, "
                    f"'high_five') or ActionClient(runner, HIGH_FIVE, 'high_five'); received "
                    f"{action!r} alone"
                )
            action_type, action_name = None, action
        elif not isinstance(action, ActionType):
            raise ConfigurationError(
                f"action_type must be an ActionType (e.g. HIGH_FIVE) when a name follows it; "
                f"received {action!r}"
            )
        else:
            action_type = action
        if not isinstance(runner, ActionRunner):
            held = getattr(runner, "runner", None)
            if not isinstance(held, ActionRunner):
                raise ConfigurationError(
                    f"runner must be an ActionRunner or hold one as .runner (e.g. a "
                    f"ControlLoop); received {runner!r}"
                )
            runner = held
        self._runner = runner
        self._server = runner.server(action_name)
        if action_type is not None and action_type != self._server.action_type:
            raise ConfigurationError(
                f"action '{action_name}' serves the {self._server.action_type.name} interface; "
                f"received action_type {action_type.name}"
            )

    @property
    def action_name(self) -> str:
        """The action this client talks to."""
        return self._server.action_name

    @property
    def action_type(self) -> ActionType:
        """The action's interface (``.Goal`` builds a goal)."""
        return self._server.action_type

    def server_is_ready(self) -> bool:
        """Whether the server takes goals: its runner has not been shut down.

        The server lives in this process and is found when the client is made, so unlike
        rclpy's there is no discovery to wait for.
        """
        return not self._runner.is_shut_down

    def wait_for_server(self, timeout_sec: float | None = None) -> bool:
        """Wait until the server is ready (rclpy's ``wait_for_server``); here it never waits.

        The server was found when the client was made, so this returns
        :meth:`server_is_ready` at once: ``True``, or ``False`` after the runner was shut
        down, which a wait could not change (a runner never restarts). Goals are processed
        on the control tick, so whoever ticks the runner must keep doing so.

        Args:
            timeout_sec: Longest wait [s]: ``None`` (no limit) or a finite number >= 0.
                Accepted for rclpy's signature.

        Returns:
            Whether the server is ready.

        Raises:
            ConfigurationError: ``timeout_sec`` is neither ``None`` nor a finite number >= 0.
        """
        if timeout_sec is not None and (not is_finite_real(timeout_sec) or timeout_sec < 0):
            raise ConfigurationError(
                f"timeout_sec must be None or a finite number of seconds >= 0; received "
                f"{timeout_sec!r}"
            )
        return self.server_is_ready()

    def send_goal_async(
        self,
        goal: GoalT,
        feedback_callback: Callable[[FeedbackMessage[FeedbackT]], None] | None = None,
    ) -> Future[ClientGoalHandle[GoalT, ResultT]]:
        """Send a goal; the future resolves on the tick that accepts or rejects it.

        Args:
            goal: A message of the action's goal type.
            feedback_callback: Called on the ticking thread with a :class:`FeedbackMessage`
                for every feedback the goal publishes, in order, after the tick's state
                change. Exceptions are logged and ignored.

        The goal is checked and copied now (the server works on its own copy, so changing
        ``goal`` afterwards changes nothing); a goal filled field by field gets the same
        errors as one built with keywords.

        Raises:
            ConfigurationError: ``goal`` is not the action's goal type, or one of its fields
                has the wrong type (the message names the field, what was received and what
                is valid).
        """
        return self._runner.submit_goal(self._server, goal, feedback_callback)

    def cancel(self, goal_handle: ClientGoalHandle[Any, Any]) -> Future[CancelResponse]:
        """Ask to cancel a goal; same as ``goal_handle.cancel_goal_async()``."""
        return goal_handle.cancel_goal_async()

    def send_goal_and_wait(
        self,
        goal: GoalT,
        timeout: float | None = None,
        feedback_callback: Callable[[FeedbackMessage[FeedbackT]], None] | None = None,
        *,
        stall_timeout_s: float = 2.0,
    ) -> WrappedResult[ResultT]:
        """Send a goal and block until it ends.

        How it makes progress:

        * If this thread registered a spin hook (``runner.set_spinner(loop.spin_once)``), it
          calls ``spin_once()`` itself until the goal ends (as
          ``rclpy.spin_until_future_complete`` does); ``timeout`` is in **simulated**
          seconds, measured on :attr:`ActionRunner.now_s`.
        * Otherwise another thread must be ticking the runner; ``timeout`` is in
          **wall-clock** seconds.

        Args:
            goal: A message of the action's goal type.
            timeout: Longest wait [s], ``None`` for no limit.
            feedback_callback: As in :meth:`send_goal_async`.
            stall_timeout_s: Without a spin hook: give up after this many wall-clock seconds
                [s] without a single tick.

        Returns:
            The goal's terminal status and result.

        Raises:
            GoalRejectedError: The goal was rejected (code and message attached).
            ActionTimeoutError: ``timeout`` expired. The goal is NOT cancelled: it keeps
                running; cancel it with ``client.cancel(err.goal_handle)``.
            RunnerStalledError: Nothing ticks the runner (no tick for ``stall_timeout_s``
                and no spin hook on this thread), or the spin hook does not tick it.
            ActionUsageError: Called on the ticking thread (from a callback): it would wait
                for a tick that cannot happen.
            ConfigurationError: ``goal``, ``timeout`` or ``stall_timeout_s`` is invalid.
        """
        if self._runner.in_tick_thread():
            raise ActionUsageError(
                "send_goal_and_wait was called from inside a tick callback, where it would "
                "wait forever for the next tick; use send_goal_async with a done callback"
            )
        _check_seconds("timeout", timeout, allow_none=True)
        _check_seconds("stall_timeout_s", stall_timeout_s, allow_none=False)
        waiter = _Waiter(self._runner, timeout, stall_timeout_s)
        handle_future = self.send_goal_async(goal, feedback_callback)
        handle: ClientGoalHandle[GoalT, ResultT] | None = None
        try:
            handle = waiter.wait(
                handle_future,
                lambda: ActionTimeoutError(
                    f"the goal request to '{self.action_name}' was not processed within "
                    f"{timeout:g} s of {waiter.clock} time; it is still queued and may be "
                    "accepted by a later tick (it has NOT been withdrawn): use "
                    "err.goal_handle_future to cancel it once accepted"
                ),
                f"the goal request to '{self.action_name}'",
            )
            if handle.rejection is not None:  # rejected (accepted is False)
                raise GoalRejectedError(handle.goal_id, handle.action_name, handle.rejection)
            return waiter.wait(
                handle.get_result_async(),
                lambda: ActionTimeoutError(
                    f"goal {handle.goal_id} ({self.action_name}) did not finish within "
                    f"{timeout:g} s of {waiter.clock} time; it is still {handle.status.name} "
                    "and has NOT been cancelled: cancel it with client.cancel(err.goal_handle)"
                ),
                f"goal {handle.goal_id} ({self.action_name})",
            )
        except ActionTimeoutError as err:
            err.goal_handle, err.goal_handle_future = handle, handle_future
            raise


class _Waiter:
    """Waits for futures of one blocking call, spinning or blocking, against one deadline."""

    def __init__(self, runner: ActionRunner, timeout: float | None, stall_timeout_s: float):
        self._runner = runner
        self._timeout = timeout
        self._stall_timeout_s = stall_timeout_s
        self._spinner = runner.spinner_for_current_thread()
        self._start_sim_s = runner.now_s
        self._start_wall_s = time.monotonic()

    @property
    def clock(self) -> str:
        """Which clock ``timeout`` is measured on."""
        return "simulated" if self._spinner is not None else "wall-clock"

    def wait(self, future: Future[T], on_timeout: Callable[[], ActionTimeoutError], what: str) -> T:
        if self._spinner is not None:
            return self._spin(future, on_timeout, self._spinner)
        return self._block(future, on_timeout, what)

    def _spin(
        self,
        future: Future[T],
        on_timeout: Callable[[], ActionTimeoutError],
        spinner: Callable[[], object],
    ) -> T:
        while not future.done():
            now_s = self._runner.now_s
            if self._start_sim_s is None:
                self._start_sim_s = now_s
            start_s = self._start_sim_s
            if (
                self._timeout is not None
                and now_s is not None
                and start_s is not None
                and now_s - start_s >= self._timeout
            ):
                raise on_timeout()
            ticks = self._runner.tick_count
            spinner()
            if self._runner.tick_count == ticks:
                raise RunnerStalledError(
                    f"the spin hook {spinner!r} returned without ticking the runner; "
                    "spin_once must advance the control loop, ticking its runner at the loop's time"
                )
        return future.result()

    def _block(
        self, future: Future[T], on_timeout: Callable[[], ActionTimeoutError], what: str
    ) -> T:
        while True:
            window = self._stall_timeout_s
            if self._timeout is not None:
                remaining = self._start_wall_s + self._timeout - time.monotonic()
                if remaining <= 0:
                    raise on_timeout()
                window = min(window, remaining)
            ticks = self._runner.tick_count
            try:
                return future.result(timeout=window)
            except FutureTimeoutError:
                if window >= self._stall_timeout_s and self._runner.tick_count == ticks:
                    raise RunnerStalledError(
                        f"nothing is ticking the runner: no tick in {window:g} s (wall-clock) "
                        f"while waiting for {what}, and this thread registered no spin hook. "
                        "Tick the runner at the loop's time from a control loop thread, or "
                        "register the loop's spin_once with runner.set_spinner(...) on this thread"
                    ) from None


def _check_seconds(name: str, value: Any, *, allow_none: bool) -> None:
    if value is None and allow_none:
        return
    if not is_finite_real(value) or value <= 0:
        valid = "None or a finite number of seconds > 0" if allow_none else "a finite number > 0"
        raise ConfigurationError(f"{name} must be {valid}; received {value!r}")
