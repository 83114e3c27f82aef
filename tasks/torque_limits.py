"""Joint torque limits on the torques the accelerations and contact forces imply."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock
from tasks.contact_task import ContactTask
from tasks.variable_layout import VariableLayout
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class TorqueLimits(Constraint):
    """``-tau_max <= M_a qdd + h_a - J_a^T f <= tau_max`` on the actuated joints.

    Its rows are also how the controller recovers the torques: ``tau = A_rows x + h_a``.
    """

    name = "torque limits"
    gives_torques = True

    def __init__(self, contacts: ContactTask, tau_max: np.ndarray):
        """Args:
            contacts: The contact points' task (its Jacobian maps the forces to torques).
            tau_max: Torque limit of each actuated joint [N m] (nv - 6,).
        """
        if contacts.nv is None:  # a ContactTask knows it from its model
            raise ConfigurationError("TorqueLimits: the contact task does not know the "
                                     "robot's nv; build it with the robot's model")
        self.contacts = contacts
        self._joints = contacts.nv - 6
        self._tau_max = as_vector("tau_max", tau_max, self._joints)

    @property
    def tau_max(self) -> np.ndarray:
        """Torque limit of each actuated joint [N m] (a copy)."""
        return self._tau_max.copy()

    @tau_max.setter
    def tau_max(self, value: np.ndarray) -> None:
        # In place: the bound kernel calls of every layout read this array.
        self._tau_max[:] = as_vector("tau_max", value, self._joints)

    def rows(self, layout: VariableLayout) -> int:
        return layout.nv - 6

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        return constraint_kernels.equation_of_motion_rows, (
            kinematics.mass_matrix, kinematics.nonlinear_effects, self.contacts.jacobian,
            layout.loaded, layout.force_columns, 6, block.A, block.lower, block.upper,
            self._tau_max)
