"""Base class of the whole-body QP's linear constraints: ``lower <= A x <= upper``, bounds on x."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tasks.compiled_call import bind_compiled

if TYPE_CHECKING:
    from tasks.kinematics import RobotKinematics
    from tasks.variable_layout import VariableLayout


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
        if call is not None and call[0] is kinematics and call[1] is block:
            call[2]()
            return
        compiled = self._compiled_call(kinematics, layout, block)
        if compiled is None:
            raise NotImplementedError(f"{type(self).__name__}.update")
        bound = bind_compiled(compiled[0], *compiled[1])
        self._call = (kinematics, block, bound)
        bound()

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple | None:
        """``(kernel, arguments)`` writing this constraint's entries, or ``None``."""
        return None

    #: The cached ``(kinematics, block, bound kernel)`` of a compiled constraint (see
    #: :func:`tasks.compiled_call.bind_compiled`).
    _call: tuple | None = None
