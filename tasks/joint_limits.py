"""Joint position and velocity limits as bounds on the joint accelerations."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import constraint_kernels
from tasks.constraint import Constraint, ConstraintBlock
from tasks.variable_layout import VariableLayout
from wbc.core.validation import as_float, as_vector

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class JointLimits(Constraint):
    """Accelerations that keep each joint inside its position limits over ``horizon_s`` and
    under its velocity limit after one horizon (bounds on ``qdd``, no rows)."""

    name = "joint limits"

    def __init__(self, q_low: np.ndarray, q_high: np.ndarray, v_max: np.ndarray, *,
                 horizon_s: float):
        """Args:
            q_low, q_high: Position limits [rad] of the actuated joints.
            v_max: Velocity limits [rad/s].
            horizon_s: Look-ahead of the position limits [s].
        """
        n = len(q_low)
        self.q_low = as_vector("q_low", q_low, n)
        self.q_high = as_vector("q_high", q_high, n)
        self.v_max = as_vector("v_max", v_max, n)
        self.horizon_s = as_float("horizon_s", horizon_s, low=1e-6)

    def rows(self, layout: VariableLayout) -> int:
        return 0

    def _compiled_call(self, kinematics: RobotKinematics, layout: VariableLayout,
                       block: ConstraintBlock) -> tuple:
        return constraint_kernels.joint_acceleration_bounds, (
            kinematics.q, kinematics.v, self.q_low, self.q_high, self.v_max, self.horizon_s,
            block.lb, block.ub)
