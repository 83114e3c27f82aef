"""Stance feet do not accelerate: the contact task's rows as equality constraints."""

from __future__ import annotations

from typing import TYPE_CHECKING

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock, Elimination
from tasks.contact_task import ContactTask
from tasks.variable_layout import VariableLayout

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class StanceContacts(Constraint):
    """``J_c qdd + drift = -kd v_c`` for every contact with force variables (3 rows each)."""

    name = "stance contacts"
    equality = True
    eliminable_as = Elimination.STANCE_CONTACTS

    def __init__(self, contacts: ContactTask):
        """Args:
            contacts: The contact points' task; the controller updates it before this.
        """
        self.contacts = contacts

    def rows(self, layout: VariableLayout) -> int:
        return 3 * len(layout.force_contacts)

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        task = self.contacts
        return constraint_kernels.stance_contact_rows, (
            task.jacobian, task.drift, task.desired_acceleration, layout.loaded, block.A,
            block.lower, block.upper)
