"""The centre of mass kept inside the support polygon by a soft second-order barrier."""

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

#: Largest number of polygon edges (four feet).
MAX_EDGES = 4


class SupportPolygonBarrier(Constraint):
    """For each edge ``n . p >= o`` of the polygon, the CoM distance ``d = n . c - o`` obeys
    ``d'' + 2 omega d' + omega^2 d >= -s``: a critically damped approach that never
    crosses the edge, made soft by one slack ``s >= 0`` (weighted in the cost).

    The caller sets the polygon (:meth:`set_polygon`) when the supporting feet change.
    """

    name = "support polygon"
    slacks = ("support",)

    def __init__(self, *, omega: float):
        """Args:
            omega: Natural frequency of the barrier [rad/s].
        """
        self.omega = as_float("omega", omega, low=0.0)
        self.normals = np.zeros((MAX_EDGES, 2))
        self.offsets = np.zeros(MAX_EDGES)
        self._n_edges = np.zeros(1, dtype=np.int64)  # an array: read by the cached call

    def set_polygon(self, normals: np.ndarray, offsets: np.ndarray) -> None:
        """Inward unit normals (k, 2) and offsets (k,) of the edges; ``k = 0`` disables it."""
        k = len(offsets)
        if k > MAX_EDGES or np.shape(normals) != (k, 2):
            raise ConfigurationError(f"polygon: expected at most {MAX_EDGES} edges with normals "
                                     f"(k, 2), received normals {np.shape(normals)} and "
                                     f"{k} offsets")
        self.normals[:k], self.offsets[:k], self._n_edges[0] = normals, offsets, k

    @property
    def n_edges(self) -> int:
        """Number of edges in use."""
        return int(self._n_edges[0])

    def rows(self, layout: VariableLayout) -> int:
        return MAX_EDGES

    def setup(self, layout: VariableLayout, block: ConstraintBlock) -> None:
        column = layout.slack_column("support")
        block.lb[column], block.ub[column] = 0.0, constraint_kernels.INF

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        k = kinematics
        return constraint_kernels.support_barrier_rows, (
            k.com_jacobian, k.com_position, k.com_velocity, k.com_drift, self.normals,
            self.offsets, self._n_edges, self.omega, layout.slack_column("support"), block.A,
            block.lower, block.upper)
