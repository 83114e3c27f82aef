"""What a balance controller offers the motion layer (the leg lift, the actions)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from wbc.controller.control_output import ControlOutput


@runtime_checkable
class BalanceController(Protocol):
    """The interface :class:`wbc.WholeBodyController` and :class:`wbc.PlacoController` share.

    Positions are world-frame [m], forces [N]; legs are ``FL``, ``FR``, ``RL``, ``RR``.
    """

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: targets from it, all four feet in stance."""

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick; never raises on a failed solve or a bad state."""

    def safe_command(self, v: np.ndarray, message: str) -> ControlOutput:
        """The safe fallback command (status FALLBACK, with ``message``)."""

    @property
    def stance_legs(self) -> list[str]:
        """Legs in stance."""

    def support_legs(self) -> list[str]:
        """Stance legs that are fully loaded (the support polygon's corners)."""

    @property
    def com_target(self) -> np.ndarray:
        """The centre-of-mass target (a copy)."""

    @property
    def min_normal_force_n(self) -> float:
        """Minimum normal force of a loaded stance foot."""

    @property
    def total_mass_kg(self) -> float:
        """The model's total mass."""

    @property
    def full_normal_force_n(self) -> float:
        """Normal-force bound of a fully loaded stance foot."""

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target (a copy)."""

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture target (12,), description order."""

    def set_posture_weights(self, weights: np.ndarray) -> None:
        """Per-joint multipliers of the posture weight."""

    def set_foot_weight(self, leg: str, weight: float) -> None:
        """Weight of a swing foot's position task."""

    def com_position(self) -> np.ndarray:
        """Centre of mass at the last state."""

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity at the last state."""

    def foot_position(self, leg: str) -> np.ndarray:
        """Foot frame position at the last state."""

    def foot_positions(self) -> np.ndarray:
        """The four foot frames' positions (4, 3) at the last state, in ``LEGS`` order."""

    def foot_target(self, leg: str) -> np.ndarray | None:
        """A foot's position target (a copy; ``None`` before one is set)."""

    def shoulder_position(self, leg: str) -> np.ndarray:
        """Thigh joint position at the last state."""

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass reference."""

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """Swing-foot reference."""

    def max_normal_force(self, leg: str) -> float:
        """Current normal-force bound of a foot."""

    def normal_force(self, leg: str) -> float:
        """The normal force the last solved tick gave a foot."""

    def set_max_normal_force(self, leg: str, value_n: float) -> None:
        """Normal-force bound of a stance foot (ramp it to unload or reload)."""

    def set_swing(self, leg: str) -> None:
        """Release a foot."""

    def set_stance(self, leg: str, *, max_normal_force_n: float = 0.0) -> None:
        """Make a foot a stance contact."""
