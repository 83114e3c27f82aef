"""Base class of the whole-body QP's linear constraints: ``lower <= A x <= upper``, bounds on x."""

from __future__ import annotations

import enum
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


class Elimination(enum.Enum):
    """Equality rows a problem builder may eliminate exactly before the solve, with the
    contacts' :class:`tasks.ContactTask` (``J_c``, drift, desired) and the robot's dynamics
    (``M``, ``h``): every decision variable then follows from the free ones, ``x = T z + t0``
    (:mod:`wbc.controller.qp_kernel`). A constraint that declares one promises that its rows
    are exactly these, for the contacts with force variables of its ``contacts`` task.
    """

    #: ``M_u qdd + h_u = J_u^T f``: the six unactuated rows of the equations of motion.
    FLOATING_BASE_DYNAMICS = "floating-base dynamics"
    #: ``J_c qdd = desired - drift`` for each contact with force variables (3 rows each).
    STANCE_CONTACTS = "stance contacts"


class Constraint:
    """Linear rows on the decision vector ``x`` of :class:`tasks.VariableLayout`.

    A constraint declares how many rows it needs for a layout (:meth:`rows`), the slack
    variables it adds (``slacks``) and the frames it reads (``frames``); it writes its
    entries into a :class:`ConstraintBlock` in place: the constant ones once per layout in
    :meth:`setup`, the rest every tick in :meth:`write`. ``equality`` rows have
    ``lower == upper``. ``name`` names the group in failure diagnoses.

    Two declarations let a problem builder do more with the rows than keep them:
    ``eliminable_as`` (an :class:`Elimination`: the builder may solve the rows away, which
    needs both kinds registered once each; with any of them missing it solves the full QP)
    and ``gives_torques`` (the rows are the joint torques less the nonlinear effects,
    ``M_a qdd - J_a^T f``, in joint order: the builder reads the torques from them).
    """

    #: Group name, e.g. ``"torque limits"``.
    name: str = ""
    #: Whether the rows are equalities.
    equality: bool = False
    #: Slack variables this constraint adds to the layout.
    slacks: tuple[str, ...] = ()
    #: Frames whose kinematics the constraint reads.
    frames: tuple[str, ...] = ()
    #: The rows a builder may eliminate (``None``: they stay rows of the QP); such a
    #: constraint names the contact task its rows are made of in ``contacts``.
    eliminable_as: Elimination | None = None
    #: Whether the rows are the joint torques less the nonlinear effects (see above).
    gives_torques: bool = False

    def rows(self, layout: VariableLayout) -> int:
        """Number of rows for ``layout``."""
        raise NotImplementedError(f"{type(self).__name__}.rows")

    def bind(self, kinematics: RobotKinematics) -> None:
        """Resolve frames in the kinematics (called when a controller registers it)."""

    def setup(self, layout: VariableLayout, block: ConstraintBlock) -> None:
        """Write the entries that depend on the layout only (once per layout)."""

    def __init_subclass__(cls, **kwargs: object) -> None:
        super().__init_subclass__(**kwargs)
        if "update" in vars(cls):  # the method's name before this release
            raise TypeError(f"{cls.__name__}.update: a constraint writes its tick's entries in "
                            "write(kinematics, layout, block) (renamed from update); rename "
                            "the method")

    def write(self, kinematics: RobotKinematics, layout: VariableLayout,
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
        the first tick in a layout does not); a constraint that overrides :meth:`write`
        gets that method with these arguments. Its arrays are read when it runs, but
        scalars are taken as they are now: a constraint whose setters change a value the
        call reads must change an array in place.
        """
        if type(self).write is not Constraint.write:
            return functools.partial(self.write, kinematics, layout, block)
        compiled = self._compiled_call(kinematics, layout, block)
        if compiled is None:
            raise NotImplementedError(f"{type(self).__name__}.write")
        return bind_compiled(compiled[0], *compiled[1])

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple | None:
        """``(kernel, arguments)`` writing this constraint's entries, or ``None``."""
        return None

    #: The cached ``(kinematics, block, bound kernel)`` of a compiled constraint (see
    #: :func:`wbc.core.compiled_call.bind_compiled`).
    _call: tuple | None = None
