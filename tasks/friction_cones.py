"""Friction pyramids and normal-force bounds of the loaded contacts."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock
from tasks.variable_layout import VariableLayout
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class FrictionCones(Constraint):
    """``|f_x|, |f_y| <= mu f_z`` (four rows per loaded contact, world axes, flat ground)
    and ``min(f_min, f_max) <= f_z <= f_max`` as bounds on the force variables.

    ``max_force`` (one entry per contact of the layout, [N]) is read every tick: a caller
    ramps a foot's maximum down to unload it before lifting it.
    """

    name = "friction"

    def __init__(self, n_contacts: int, *, mu: float, min_force_n: float, max_force_n: float,
                 max_force: np.ndarray | None = None):
        """Args:
            n_contacts: Number of contacts of the layouts it will serve.
            mu: Friction coefficient of the pyramid.
            min_force_n: Minimum normal force of a loaded contact [N].
            max_force_n: Initial maximum normal force of every contact [N].
            max_force: An array (n_contacts,) of float64 that another object updates in
                place and this constraint reads every tick (a contact schedule's bounds);
                by default one of its own, filled with ``max_force_n``.
        """
        self.mu = as_float("mu", mu, low=0.0)
        self.min_force_n = as_float("min_force_n", min_force_n, low=0.0)
        limit = as_float("max_force_n", max_force_n, low=0.0)
        if max_force is None:
            max_force = np.full(n_contacts, limit)
        elif (not isinstance(max_force, np.ndarray) or max_force.shape != (n_contacts,)
              or max_force.dtype != np.float64):
            raise ConfigurationError(
                f"max_force: expected a float64 array of shape ({n_contacts},) to read in "
                f"place, received {type(max_force).__name__} {np.shape(max_force)}")
        #: Each contact's maximum normal force [N], read every tick (update it in place).
        self.max_force = max_force

    def rows(self, layout: VariableLayout) -> int:
        return 4 * len(layout.force_contacts)

    def setup(self, layout: VariableLayout, block: ConstraintBlock) -> None:
        A, mu = block.A, self.mu
        for k, c in enumerate(layout.force_columns[layout.loaded]):
            for axis in range(2):
                row = 4 * k + 2 * axis
                A[row, c + axis], A[row, c + 2] = 1.0, -mu          # f_t - mu f_z <= 0
                block.upper[row] = 0.0
                A[row + 1, c + axis], A[row + 1, c + 2] = 1.0, mu   # f_t + mu f_z >= 0
                block.lower[row + 1] = 0.0

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        return constraint_kernels.normal_force_bounds, (
            layout.loaded, layout.force_columns, self.min_force_n, self.max_force, block.lb,
            block.ub)
