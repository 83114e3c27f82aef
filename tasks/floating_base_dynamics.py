"""The floating base's equations of motion: contact forces are the only way to move the base."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock, Elimination
from tasks.contact_task import ContactTask
from tasks.variable_layout import VariableLayout

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class FloatingBaseDynamics(Constraint):
    """``M_u qdd + h_u = J_u^T f``: the six unactuated rows of the equations of motion.

    ``J_u`` are the base columns of the contact Jacobians of ``contacts`` (a
    :class:`ContactTask` whose frames are the layout's contacts, in order), for the
    contacts with force variables.
    """

    name = "dynamics"
    equality = True
    eliminable_as = Elimination.FLOATING_BASE_DYNAMICS

    def __init__(self, contacts: ContactTask):
        """Args:
            contacts: The contact points' task; the controller updates it before this.
        """
        self.contacts = contacts
        self._zero = np.zeros(6)

    def rows(self, layout: VariableLayout) -> int:
        return 6

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        return constraint_kernels.equation_of_motion_rows, (
            kinematics.mass_matrix, kinematics.nonlinear_effects, self.contacts.jacobian,
            layout.loaded, layout.force_columns, 0, block.A, block.lower, block.upper,
            self._zero)
