"""Where each decision variable of the whole-body QP lives: accelerations, contact forces, slacks."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wbc.core.errors import ConfigurationError


class VariableLayout:
    """The decision vector ``x = [qdd (nv), forces (3 per loaded contact), slacks]``.

    Only contacts in ``force_contacts`` have force variables: a foot in the air has none,
    so the QP shrinks when a foot lifts. Built by the controller's problem builder each time
    the set of loaded contacts changes (not every tick); tasks and constraints read their
    columns from it.
    """

    def __init__(self, nv: int, contacts: Sequence[str], force_contacts: Sequence[str],
                 slacks: Sequence[str] = ()):
        """Args:
            nv: Number of generalized accelerations.
            contacts: Every contact the robot may use, e.g. the four feet, in a fixed order.
            force_contacts: Those with force variables now (a subset, any order; stored in
                the order of ``contacts``).
            slacks: Names of the slack variables the constraints asked for.
        """
        unknown = sorted(set(force_contacts) - set(contacts))
        if unknown:
            raise ConfigurationError(f"force_contacts: unknown contact(s) {unknown}; "
                                     f"valid contacts: {list(contacts)}")
        if len(set(slacks)) != len(slacks):
            raise ConfigurationError(f"slacks: names must be unique, received {list(slacks)}")
        self.nv = nv
        self.contacts = tuple(contacts)
        self.force_contacts = tuple(c for c in contacts if c in set(force_contacts))
        self.slacks = tuple(slacks)
        self.qdd = slice(0, nv)
        self.force_start = nv
        self.slack_start = nv + 3 * len(self.force_contacts)
        self.n = self.slack_start + len(self.slacks)
        #: First force column of each contact of ``contacts`` (-1 without force variables).
        self.force_columns = np.full(len(self.contacts), -1, dtype=np.int64)
        for k, name in enumerate(self.force_contacts):
            self.force_columns[self.contacts.index(name)] = nv + 3 * k
        #: Indices (in ``contacts``) of the contacts with force variables, in column order.
        self.loaded = np.array([self.contacts.index(c) for c in self.force_contacts],
                               dtype=np.int64)

    @property
    def key(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """What identifies the layout: its loaded contacts and slacks."""
        return self.force_contacts, self.slacks

    def force_slice(self, contact: str) -> slice | None:
        """The three force columns (world x, y, z) [N] of a contact; ``None`` if it has none."""
        if contact not in self.contacts:
            raise ConfigurationError(
                f"contact: unknown contact {contact!r}; valid contacts: {list(self.contacts)}")
        start = int(self.force_columns[self.contacts.index(contact)])
        return None if start < 0 else slice(start, start + 3)

    def slack_column(self, name: str) -> int:
        """The column of a slack variable."""
        if name not in self.slacks:
            raise ConfigurationError(
                f"slack: unknown slack {name!r}; valid slacks: {list(self.slacks)}")
        return self.slack_start + self.slacks.index(name)

    def __repr__(self) -> str:
        return (f"VariableLayout(n={self.n}: qdd {self.nv}, forces {list(self.force_contacts)}, "
                f"slacks {list(self.slacks)})")
