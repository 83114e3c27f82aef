"""The joint torques as constraint rows without bounds, for a problem builder without torque
limits."""

from __future__ import annotations

import numpy as np

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock
from tasks.contact_task import ContactTask
from tasks.variable_layout import VariableLayout
from wbc.model.kinematics import RobotKinematics


class JointTorques(Constraint):
    """The joint torques as rows without bounds, for a builder that has no constraint that
    ``gives_torques`` (torque limits) registered: it needs them to recover the torques."""

    name = "joint torques"
    gives_torques = True

    def __init__(self, contacts: ContactTask):
        self.contacts = contacts
        self._unbounded = np.full(contacts.nv - 6, constraint_kernels.INF)

    def rows(self, layout: VariableLayout) -> int:
        return layout.nv - 6

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        return constraint_kernels.equation_of_motion_rows, (
            kinematics.mass_matrix, kinematics.nonlinear_effects, self.contacts.jacobian,
            layout.loaded, layout.force_columns, 6, block.A, block.lower, block.upper,
            self._unbounded)
