"""Where each leg's shoulder is, and which foot targets a leg can reach from it."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numba
import numpy as np
import pinocchio as pin

from wbc.core.errors import ConfigurationError, ReachabilityError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import Go2Description

#: Thigh + calf length of a GO2 leg [m], less a margin that keeps the knee bent.
LEG_REACH_M = 0.40

#: The base's world rotation (3, 3) and position (3,) at the last state, or ``None``.
Placement = tuple[np.ndarray, np.ndarray] | None


@numba.njit("f8(f8[:, :], f8[:], f8[::1], f8[:])", cache=True)
def _shoulder_distance(rotation, base, shoulder_in_base, position):  # pragma: no cover
    """Distance [m] from the shoulder (``base + rotation @ shoulder_in_base``) to ``position``;
    NaN when ``position`` is not 3 finite numbers."""
    if position.size != 3:
        return math.nan
    total = 0.0
    for r in range(3):
        shoulder = base[r]
        for c in range(3):
            shoulder += rotation[r, c] * shoulder_in_base[c]
        offset = position[r] - shoulder
        total += offset * offset
    return math.sqrt(total)  # NaN or inf for a non-finite position


class FootReach:
    """Each leg's shoulder (where its thigh joint sits in the standing pose, fixed to the
    base) and the foot targets within :data:`LEG_REACH_M` of it."""

    def __init__(self, description: Go2Description, legs: Sequence[str]):
        """Args:
            description: The robot (its standing pose and thigh joints).
            legs: The legs, each with a ``<leg>_thigh_joint``.
        """
        self.legs = tuple(legs)
        model = description.model
        standing = model.createData()
        pin.forwardKinematics(model, standing, description.pose("standing"))
        # The shoulder is fixed to the base: where the thigh joint sits in the standing pose
        # (the thigh joint itself swings with the hip's abduction).
        self._shoulder_in_base = {
            leg: np.array(standing.oMi[1].actInv(
                standing.oMi[model.getJointId(f"{leg}_thigh_joint")].translation), dtype=float)
            for leg in self.legs
        }

    def shoulder_in_base(self, leg: str) -> np.ndarray:
        """A leg's shoulder (3,) [m] in the base frame (a copy): for compiled code that
        checks a leg's reach itself."""
        check_name("leg", leg, self.legs)
        return self._shoulder_in_base[leg].copy()

    def shoulder_position(self, leg: str, placement: Placement) -> np.ndarray:
        """World position [m] of a leg's shoulder for the base's ``placement``.

        Raises:
            ConfigurationError: No placement yet (no state).
        """
        check_name("leg", leg, self.legs)
        if placement is None:
            raise ConfigurationError("shoulder_position: no state yet; call reset(q) first")
        rotation, position = placement
        return rotation @ self._shoulder_in_base[leg] + position

    def reachable_target(self, leg: str, position: np.ndarray, placement: Placement, *,
                         clamp: bool) -> np.ndarray:
        """The validated foot target: clamped onto the leg's reach, or refused beyond it.

        It may be ``position`` itself (not a copy): callers copy it into their task.
        Without a placement (no state yet), only its shape and values are checked.

        Raises:
            ReachabilityError: Farther than :data:`LEG_REACH_M` from the shoulder (unless
                ``clamp``); nothing is changed.
        """
        check_name("leg", leg, self.legs)
        if placement is None:
            return as_vector(f"{leg}_foot target", position, 3)
        rotation, base = placement
        try:  # float64 vectors, every tick of a swing: one compiled call, no copy
            if _shoulder_distance(rotation, base, self._shoulder_in_base[leg],
                                  position) <= LEG_REACH_M:
                return position
        except TypeError:
            pass
        position = as_vector(f"{leg}_foot target", position, 3)
        shoulder = rotation @ self._shoulder_in_base[leg] + base
        offset = position - shoulder
        distance = math.sqrt(offset @ offset)
        if distance > LEG_REACH_M and clamp:
            return shoulder + (position - shoulder) * (LEG_REACH_M / distance)
        if distance > LEG_REACH_M:
            raise ReachabilityError(
                f"{leg}_foot target: {position.round(3).tolist()} is {distance:.3f} m from "
                f"the {leg} shoulder; reachable: at most {LEG_REACH_M:.2f} m")
        return position
