"""Which feet stand and how much each may carry: the bookkeeping both controllers share."""

from __future__ import annotations

import math

import numba
import numpy as np
import pinocchio as pin

from wbc.controller.controller_config import ControllerConfig
from wbc.core.errors import ConfigurationError, ReachabilityError
from wbc.core.validation import as_float, as_vector, check_name
from wbc.model.description import LEGS, Go2Description

#: Thigh + calf length of a GO2 leg [m], less a margin that keeps the knee bent.
LEG_REACH_M = 0.40


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


class ContactModes:
    """Stance and swing feet, normal-force bounds, shoulders and foot-target reach checks.

    A base class of :class:`wbc.WholeBodyController` and :class:`wbc.PlacoController`.
    Subclasses call :meth:`_init_contact_modes` and implement two hooks:
    ``_contact_mode_changed(leg)`` (a foot's mode or bound changed) and
    ``_base_placement()`` (the base's world rotation and position at the last state, or
    ``None`` before any state).
    """

    config: ControllerConfig
    description: Go2Description

    def _init_contact_modes(self) -> None:
        self._stance = dict.fromkeys(LEGS, True)
        self._max_force = dict.fromkeys(LEGS, self.config.max_normal_force_n)
        model = self.description.model
        standing = model.createData()
        pin.forwardKinematics(model, standing, self.description.pose("standing"))
        # The shoulder is fixed to the base: where the thigh joint sits in the standing pose
        # (the thigh joint itself swings with the hip's abduction).
        self._shoulder_in_base = {
            leg: np.array(standing.oMi[1].actInv(
                standing.oMi[model.getJointId(f"{leg}_thigh_joint")].translation), dtype=float)
            for leg in LEGS
        }

    def _contact_mode_changed(self, leg: str) -> None:
        raise NotImplementedError

    def _base_placement(self) -> tuple[np.ndarray, np.ndarray] | None:
        raise NotImplementedError

    def foot_position(self, leg: str) -> np.ndarray:
        """World position [m] of a foot frame (sphere centre) at the last state."""
        raise NotImplementedError

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """World target [m], velocity [m/s] and feed-forward acceleration of a swing foot."""
        raise NotImplementedError

    # ------------------------------------------------------------------ modes

    @property
    def stance_legs(self) -> list[str]:
        """Legs currently in stance."""
        return [leg for leg in LEGS if self._stance[leg]]

    def support_legs(self) -> list[str]:
        """Stance legs that are fully loaded: the corners of the support polygon."""
        full = self.config.max_normal_force_n
        return [leg for leg in LEGS if self._stance[leg] and self._max_force[leg] >= full]

    def normal_force_bounds(self, out: np.ndarray) -> np.ndarray:
        """Each foot's normal-force bound [N] into ``out`` (4,), ``LEGS`` order, 0 in swing:
        the contact schedule a state estimator reads (:class:`wbc.StateEstimator`)."""
        stance, bound = self._stance, self._max_force
        for i, leg in enumerate(LEGS):
            out[i] = bound[leg] if stance[leg] else 0.0
        return out

    def max_normal_force(self, leg: str) -> float:
        """Current upper bound [N] of a foot's normal force."""
        check_name("leg", leg, LEGS)
        return self._max_force[leg]

    @property
    def min_normal_force_n(self) -> float:
        """The minimum normal force [N] of a loaded stance foot."""
        return self.config.min_normal_force_n

    @property
    def full_normal_force_n(self) -> float:
        """The normal-force bound [N] of a fully loaded stance foot."""
        return self.config.max_normal_force_n

    @property
    def total_mass_kg(self) -> float:
        """The model's total mass [kg]."""
        return self.description.total_mass

    def _checked_force(self, leg: str, value_n: float) -> float:
        return as_float(f"{leg} max_normal_force_n", value_n, low=0.0,
                        high=self.config.max_normal_force_n)

    def set_max_normal_force(self, leg: str, value_n: float) -> None:
        """Upper bound [N] of a stance foot's normal force (ramp it to unload or reload)."""
        check_name("leg", leg, LEGS)
        value = self._checked_force(leg, value_n)
        if not self._stance[leg]:
            raise ConfigurationError(
                f"leg: {leg} is in swing; call set_stance({leg!r}) before loading it"
            )
        self._max_force[leg] = value
        self._contact_mode_changed(leg)

    def set_swing(self, leg: str) -> None:
        """Release a foot: no contact force, its position task takes over.

        Its target starts at its current position. At least three feet must stay in stance.
        """
        check_name("leg", leg, LEGS)
        if self._stance[leg] and sum(self._stance.values()) <= 3:
            raise ConfigurationError(
                f"leg: cannot release {leg}: at least three feet must stay in stance "
                f"(stance now: {', '.join(self.stance_legs)})"
            )
        if self._stance[leg] and self._base_placement() is not None:
            self.set_foot_target(leg, self.foot_position(leg))
        self._stance[leg] = False
        self._max_force[leg] = 0.0
        self._contact_mode_changed(leg)

    def set_stance(self, leg: str, *, max_normal_force_n: float = 0.0) -> None:
        """Make a foot a stance contact with the given maximum normal force [N].

        Start at zero and ramp it up with :meth:`set_max_normal_force` for a smooth touch-down.
        """
        check_name("leg", leg, LEGS)
        self._max_force[leg] = self._checked_force(leg, max_normal_force_n)
        self._stance[leg] = True
        self._contact_mode_changed(leg)

    # ------------------------------------------------------------------ reach

    def shoulder_position(self, leg: str) -> np.ndarray:
        """World position [m] of a leg's shoulder (fixed to the base) at the last state."""
        check_name("leg", leg, LEGS)
        placement = self._base_placement()
        if placement is None:
            raise ConfigurationError("shoulder_position: no state yet; call reset(q) first")
        rotation, position = placement
        return rotation @ self._shoulder_in_base[leg] + position

    def _reachable_target(self, leg: str, position: np.ndarray,
                          clamp_to_reach: bool) -> np.ndarray:
        """The validated foot target: clamped onto the leg's reach, or refused beyond it.

        It may be ``position`` itself (not a copy): callers copy it into their task.

        Raises:
            ReachabilityError: Farther than :data:`LEG_REACH_M` from the shoulder (unless
                clamping); nothing is changed.
        """
        check_name("leg", leg, LEGS)
        placement = self._base_placement()
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
        if distance > LEG_REACH_M and clamp_to_reach:
            return shoulder + (position - shoulder) * (LEG_REACH_M / distance)
        if distance > LEG_REACH_M:
            raise ReachabilityError(
                f"{leg}_foot target: {position.round(3).tolist()} is {distance:.3f} m from "
                f"the {leg} shoulder; reachable: at most {LEG_REACH_M:.2f} m"
            )
        return position
