"""``go2-wbc send-goal --dds`` and ``go2-wbc high-five --dds``: one goal to the action servers
of a controller on DDS (``go2-wbc run --dds``), printed as ``ros2 action send_goal`` prints it.

The output is ``send-goal``'s against a simulated GO2, with feedback times in wall-clock
seconds since the goal was sent. The exit status is the result's: 0 SUCCEEDED, 1 CANCELED or
ABORTED (or no result in time), 3 rejected, 4 no action server matched (the client's message
says what it saw on the domain), 130 Ctrl-C (the goal is canceled first; a second Ctrl-C
leaves at once, and the server cancels the goal of a client that went away).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import signal
import sys
import threading
import time
from concurrent.futures import TimeoutError as FutureTimeoutError
from typing import IO, Any

import yaml

from actions.client_goal_handle import ClientGoalHandle
from actions.dds.dds_action_client import ActionServerUnavailableError, DdsActionClient
from actions.go2.go2_actions import GO2_ACTIONS, HIGH_FIVE_ACTION
from actions.go2.go2_interfaces import HighFiveGoal
from actions.goal_status import GoalStatus
from actions.responses import FeedbackMessage, WrappedResult
from sim.cli.exit_codes import (
    EXIT_INTERRUPTED,
    EXIT_NOT_SUCCEEDED,
    EXIT_REJECTED,
    EXIT_SUCCEEDED,
    EXIT_UNAVAILABLE,
    EXIT_USAGE,
)
from sim.cli.send_goal import checked_goal, rounded_fields, yaml_block
from wbc.core.errors import ConfigurationError

#: Longest wait [s] for a server to match, and for a goal's acceptance.
SERVER_WAIT_S = 5.0
#: Longest wait [s] for a canceled goal's result (its unwind).
CANCEL_WAIT_S = 15.0


def send_goal(args: argparse.Namespace) -> int:
    """``go2-wbc send-goal ACTION [TYPE] GOAL --dds``: the goal checked as ``send-goal``
    checks it, then sent (:func:`send_goal_over_dds`)."""
    name, goal = checked_goal(args)
    return send_goal_over_dds(args, name, goal)


def high_five(args: argparse.Namespace) -> int:
    """``go2-wbc high-five --dds``: feedback printed when its phase changes."""
    goal = HighFiveGoal(target_height=args.height, hold_seconds=args.hold)
    return send_goal_over_dds(args, HIGH_FIVE_ACTION, goal)


def send_goal_over_dds(args: argparse.Namespace, action_name: str, goal: Any, *,
                       stream: IO[str] | None = None) -> int:
    """Send ``goal`` to ``action_name`` on ``args.domain``/``args.interface``, print its
    progress and result; return the exit status (module doc).

    ``args`` may give ``feedback`` (print every feedback message, or none; without it, a line
    when the feedback's phase changes) and ``timeout`` (wall-clock seconds before the goal is
    canceled; default none).
    """
    out = stream or sys.stdout

    def say(text: str) -> None:
        out.write(text + "\n")
        out.flush()

    # A process started in the background of a shell inherits SIGINT ignored: Ctrl-C (or
    # kill -INT) must still cancel the goal.
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        client = DdsActionClient(GO2_ACTIONS[action_name], action_name,
                                 domain_id=args.domain, interface=args.interface)
    except ConfigurationError as err:
        print(f"go2-wbc: error: {err}", file=sys.stderr)
        return EXIT_USAGE
    try:
        say(f"Waiting for an action server to become available (DDS domain {args.domain}, "
            f"interface {args.interface})...")
        if not client.wait_for_server(SERVER_WAIT_S):
            print(f"go2-wbc: {client.unavailable_reason(SERVER_WAIT_S)}", file=sys.stderr)
            return EXIT_UNAVAILABLE
        say("Sending goal:\n" + yaml_block(goal) + "\n")
        sent_s = time.monotonic()
        show = getattr(args, "feedback", None)  # None: when the phase changes
        phases: list[Any] = [None]

        def feedback(message: FeedbackMessage) -> None:
            phase = getattr(message.feedback, "phase", None)
            if show is False or (show is None and phase == phases[0]):
                return
            phases[0] = phase
            fields = rounded_fields(dataclasses.asdict(message.feedback))
            text = yaml.safe_dump(fields, default_flow_style=True, sort_keys=False,
                                  width=math.inf).strip()
            say(f"Feedback [{time.monotonic() - sent_s:7.3f} s]: {text}")

        handle = client.send_goal_async(goal, feedback).result(timeout=SERVER_WAIT_S)
        rejection = handle.rejection
        if rejection is not None:
            say(f"Goal was rejected (code {rejection.code}): {rejection.message}")
            return EXIT_REJECTED
        say(f"Goal accepted with ID: {handle.goal_id}\n")
        wrapped, interrupted = _wait_for_result(handle, getattr(args, "timeout", None), say)
        if wrapped is None:
            say(f"No result within {CANCEL_WAIT_S:g} s of the cancel; status "
                f"{handle.status.name}")
            return EXIT_INTERRUPTED if interrupted else EXIT_NOT_SUCCEEDED
        say("\nResult:\n" + yaml_block(wrapped.result) + "\n")
        say(f"Goal finished with status: {wrapped.status.name}")
        if interrupted:
            return EXIT_INTERRUPTED
        return EXIT_SUCCEEDED if wrapped.status == GoalStatus.SUCCEEDED else EXIT_NOT_SUCCEEDED
    except (ActionServerUnavailableError, FutureTimeoutError) as err:
        reason = str(err) or f"the server did not answer within {SERVER_WAIT_S:g} s"
        print(f"go2-wbc: {reason}", file=sys.stderr)
        return EXIT_UNAVAILABLE
    finally:
        client.close()


def _wait_for_result(handle: ClientGoalHandle, timeout_s: float | None,
                     say: Any) -> tuple[WrappedResult | None, bool]:
    """The goal's result, canceling it on a timeout or a Ctrl-C; whether it was a Ctrl-C."""
    future = handle.get_result_async()
    try:
        return future.result(timeout=timeout_s), False
    except FutureTimeoutError:
        say(f"No result after {timeout_s:g} s: canceling the goal")
        interrupted = False
    except KeyboardInterrupt:
        say("Interrupted: canceling the goal (Ctrl-C again to leave at once)")
        interrupted = True
    handle.cancel_goal_async()
    try:
        return future.result(timeout=CANCEL_WAIT_S), interrupted
    except FutureTimeoutError:
        return None, interrupted
