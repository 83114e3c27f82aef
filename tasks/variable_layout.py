"""Where each decision variable of the whole-body QP lives: accelerations, forces, slacks."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wbc.core.errors import ConfigurationError

#: The generalized accelerations [m/s^2, rad/s^2] (nv columns).
QDD = "qdd"
_FORCE, _SLACK = "force:", "slack:"
_VALID = ("'qdd' (nv columns), 'force:<contact>' (3 columns: world x, y, z [N]), "
          "'slack:<name>' (1 column)")


def force_variable(contact: str) -> str:
    """The name of a contact's force variables (``"force:FR"``), for a task's ``variables``."""
    return _FORCE + contact


def slack_variable(name: str) -> str:
    """The name of a slack variable (``"slack:support"``), for a task's ``variables``."""
    return _SLACK + name


def variable_width(name: str, nv: int) -> int:
    """Number of columns of the variable ``name`` (``qdd``: ``nv``; a force: 3; a slack: 1).

    Raises:
        ConfigurationError: Not a variable name; the message lists the valid forms.
    """
    if name == QDD:
        return nv
    if name.startswith(_FORCE) and len(name) > len(_FORCE):
        return 3
    if name.startswith(_SLACK) and len(name) > len(_SLACK):
        return 1
    raise ConfigurationError(f"variables: unknown variable {name!r}; valid: {_VALID}")


class VariableLayout:
    """The decision vector ``x = [qdd (nv), forces (3 per loaded contact), slacks]``.

    Only contacts in ``force_contacts`` have force variables: a foot in the air has none,
    so the QP shrinks when a foot lifts. Built by the controller's problem builder each time
    the set of loaded contacts changes (not every tick); tasks and constraints read their
    columns from it. Variables are named as a task's ``variables`` names them: ``"qdd"``,
    ``"force:<contact>"``, ``"slack:<name>"`` (:meth:`columns`).
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

    def check_variables(self, variables: Sequence[str], *, owner: str = "variables") -> None:
        """Check that each name is a variable this robot can have (a known contact's force,
        a known slack, ``qdd``); a contact that is in the air now is fine.

        Raises:
            ConfigurationError: Names ``owner`` and the variable; lists the valid ones.
        """
        for name in variables:
            variable_width(name, self.nv)
            if name.startswith(_FORCE) and name[len(_FORCE):] not in self.contacts:
                raise ConfigurationError(
                    f"{owner}: unknown contact in {name!r}; valid: "
                    f"{[force_variable(c) for c in self.contacts]}")
            if name.startswith(_SLACK) and name[len(_SLACK):] not in self.slacks:
                raise ConfigurationError(
                    f"{owner}: unknown slack in {name!r}; the constraints add the slacks "
                    f"{[slack_variable(s) for s in self.slacks]}")

    def columns(self, variables: Sequence[str]) -> np.ndarray:
        """The column of ``x`` of each column of a Jacobian over ``variables`` (int64), -1
        for a contact without force variables in this layout (its force is zero).

        Raises:
            ConfigurationError: An unknown variable, contact or slack.
        """
        self.check_variables(variables)
        parts = []
        for name in variables:
            if name == QDD:
                parts.append(np.arange(self.nv))
            elif name.startswith(_FORCE):
                start = int(self.force_columns[self.contacts.index(name[len(_FORCE):])])
                parts.append(np.arange(start, start + 3) if start >= 0 else np.full(3, -1))
            else:
                parts.append(np.array([self.slack_column(name[len(_SLACK):])]))
        return np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, np.int64)

    def __repr__(self) -> str:
        return (f"VariableLayout(n={self.n}: qdd {self.nv}, forces {list(self.force_contacts)}, "
                f"slacks {list(self.slacks)})")
