"""Base class of the whole-body QP's linear constraints: ``lower <= A x <= upper``, bounds on x."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from wbc.core.compiled_call import bind_compiled

if TYPE_CHECKING:
    from tasks.variable_layout import VariableLayout
    from wbc.model.kinematics import RobotKinematics


@dataclass
class ConstraintBlock:
    """A constraint's share of the QP, views allocated once per variable layout.

    Attributes:
        A: Its rows of the constraint matrix (rows, n), zero where it writes nothing.
        lower, upper: Its rows' bounds (``INFINITY`` for none).
        lb, ub: Bounds on the whole decision vector (n,), shared by every constraint: a
            constraint writes the entries of the variables it bounds.
        rows: Where its rows sit in the QP.
    """

    A: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    lb: np.ndarray
    ub: np.ndarray
    rows: slice


class Constraint:
    """Linear rows on the decision vector ``x`` of :class:`tasks.VariableLayout`.

    A constraint declares how many rows it needs for a layout (:meth:`rows`), the slack
    variables it adds (``slacks``) and the frames it reads (``frames``); it writes its
    entries into a :class:`ConstraintBlock` in place: the constant ones once per layout in
    :meth:`setup`, the rest every tick in :meth:`update`. ``equality`` rows have
    ``lower == upper``. ``name`` names the group in failure diagnoses.
    """

    #: Group name, e.g. ``"torque limits"``.
    name: str = ""
    #: Whether the rows are equalities.
    equality: bool = False
    #: Slack variables this constraint adds to the layout.
    slacks: tuple[str, ...] = ()
    #: Frames whose kinematics the constraint reads.
    frames: tuple[str, ...] = ()

    def rows(self, layout: VariableLayout) -> int:
        """Number of rows for ``layout``."""
        raise NotImplementedError(f"{type(self).__name__}.rows")

    def bind(self, kinematics: RobotKinematics) -> None:
        """Resolve frames in the kinematics (called when a controller registers it)."""

    def setup(self, layout: VariableLayout, block: ConstraintBlock) -> None:
        """Write the entries that depend on the layout only (once per layout)."""

    def update(self, kinematics: RobotKinematics, layout: VariableLayout,
               block: ConstraintBlock) -> None:
        """Write this tick's entries at the last state.

        Override it, or (built-in constraints) :meth:`_compiled_call`: its kernel and
        arguments are gathered once per kinematics and block.
        """
        call = self._call
        if call is None or call[0] is not kinematics or call[1] is not block:
            call = self._call = (kinematics, block, self.tick_call(kinematics, layout, block))
        call[2]()

    def tick_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                  block: ConstraintBlock) -> Callable[[], None]:
        """A callable of no arguments that writes this tick's entries into ``block``.

        A problem builder keeps one per layout and calls it every tick. A built-in
        constraint's is its compiled kernel bound to its arrays
        (:func:`wbc.core.compiled_call.bind_compiled`; getting it loads the compiled code, so
        the first tick in a layout does not); a constraint that overrides :meth:`update`
        gets that method with these arguments. Its arrays are read when it runs, but
        scalars are taken as they are now: a constraint whose setters change a value the
        call reads must change an array in place.
        """
        if type(self).update is not Constraint.update:
            return functools.partial(self.update, kinematics, layout, block)
        compiled = self._compiled_call(kinematics, layout, block)
        if compiled is None:
            raise NotImplementedError(f"{type(self).__name__}.update")
        return bind_compiled(compiled[0], *compiled[1])

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple | None:
        """``(kernel, arguments)`` writing this constraint's entries, or ``None``."""
        return None

    #: The cached ``(kinematics, block, bound kernel)`` of a compiled constraint (see
    #: :func:`wbc.core.compiled_call.bind_compiled`).
    _call: tuple | None = None
