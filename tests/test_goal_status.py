"""Tests of the goal status codes and the transition table."""

from __future__ import annotations

import itertools

import pytest

from actions.errors import IllegalTransitionError
from actions.goal_status import (
    LEGAL_TRANSITIONS,
    TERMINAL_STATUSES,
    GoalStatus,
    check_transition,
    legal_next_statuses,
)
from wbc.core.errors import WbcError

S = GoalStatus

EXPECTED_LEGAL = {
    (S.UNKNOWN, S.ACCEPTED),
    (S.ACCEPTED, S.EXECUTING),
    (S.ACCEPTED, S.CANCELING),
    (S.ACCEPTED, S.ABORTED),
    (S.EXECUTING, S.CANCELING),
    (S.EXECUTING, S.SUCCEEDED),
    (S.EXECUTING, S.ABORTED),
    (S.CANCELING, S.CANCELED),
    (S.CANCELING, S.ABORTED),
}


def test_numbers_match_action_msgs_goal_status() -> None:
    assert {status.name: int(status) for status in GoalStatus} == {
        "UNKNOWN": 0,
        "ACCEPTED": 1,
        "EXECUTING": 2,
        "CANCELING": 3,
        "SUCCEEDED": 4,
        "CANCELED": 5,
        "ABORTED": 6,
    }


def test_is_terminal() -> None:
    assert {status for status in GoalStatus if status.is_terminal} == {
        S.SUCCEEDED,
        S.CANCELED,
        S.ABORTED,
    }
    assert TERMINAL_STATUSES == {S.SUCCEEDED, S.CANCELED, S.ABORTED}


def test_table_is_exactly_the_documented_transitions() -> None:
    table = {(old, new) for old, news in LEGAL_TRANSITIONS.items() for new in news}
    assert table == EXPECTED_LEGAL
    assert set(LEGAL_TRANSITIONS) == set(GoalStatus)
    for status in TERMINAL_STATUSES:
        assert legal_next_statuses(status) == frozenset()


@pytest.mark.parametrize("old, new", sorted(EXPECTED_LEGAL))
def test_every_legal_transition_passes(old: GoalStatus, new: GoalStatus) -> None:
    check_transition(old, new)


ILLEGAL = sorted(set(itertools.product(GoalStatus, GoalStatus)) - EXPECTED_LEGAL)


@pytest.mark.parametrize("old, new", ILLEGAL)
def test_every_illegal_transition_raises_naming_both_states(
    old: GoalStatus, new: GoalStatus
) -> None:
    with pytest.raises(IllegalTransitionError) as info:
        check_transition(old, new)
    assert f"{old.name} -> {new.name}" in str(info.value)
    assert isinstance(info.value, WbcError)


def test_illegal_transition_message_lists_the_legal_next_states() -> None:
    with pytest.raises(IllegalTransitionError) as info:
        check_transition(S.CANCELING, S.SUCCEEDED)
    assert str(info.value) == (
        "illegal goal status transition CANCELING -> SUCCEEDED; "
        "legal next statuses from CANCELING: CANCELED, ABORTED"
    )


def test_transition_out_of_a_terminal_state_says_it_is_terminal() -> None:
    with pytest.raises(IllegalTransitionError) as info:
        check_transition(S.SUCCEEDED, S.EXECUTING)
    assert str(info.value) == (
        "illegal goal status transition SUCCEEDED -> EXECUTING; "
        "SUCCEEDED is terminal: no further status change is legal"
    )


def test_action_msgs_constant_names_are_aliases() -> None:
    assert GoalStatus.STATUS_SUCCEEDED is S.SUCCEEDED and GoalStatus.STATUS_UNKNOWN is S.UNKNOWN
    assert [status.name for status in GoalStatus] == [
        "UNKNOWN", "ACCEPTED", "EXECUTING", "CANCELING", "SUCCEEDED", "CANCELED", "ABORTED",
    ]  # iteration and names are unchanged
    assert all(
        getattr(GoalStatus, f"STATUS_{status.name}") is status for status in GoalStatus
    )
