"""What a balance controller offers the motions, the behaviours and the robot loop."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.control_output import ControlOutput
from wbc.model.description import Go2Description


@runtime_checkable
class BalanceController(Protocol):
    """The members :class:`wbc.WholeBodyController` and :class:`wbc.PlacoController` share,
    and all that the leg lift, the posture transitions, the behaviours and the robot loop
    use of a controller.

    Positions are world-frame [m], forces [N]; legs are ``FL``, ``FR``, ``RL``, ``RR``.
    Which feet stand and how much each may carry is the controller's :attr:`schedule`
    (:class:`ContactSchedule`: ``stance_legs``, ``support_legs()``, ``set_swing``,
    ``set_stance``, ``ramp_normal_force``, ``normal_force_bounds``, ...).
    """

    @property
    def schedule(self) -> ContactSchedule:
        """The contact schedule: feet in stance or swing, normal-force bounds and ramps."""

    @property
    def description(self) -> Go2Description:
        """The robot: joints, poses, limits, mass."""

    @property
    def control_period_s(self) -> float:
        """The period [s] the controller runs at."""

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: targets from it, every foot in stance."""

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick; never raises on a failed solve or a bad state."""

    def safe_command(self, v: np.ndarray, message: str) -> ControlOutput:
        """The safe fallback command (status FALLBACK, with ``message``)."""

    @property
    def com_target(self) -> np.ndarray:
        """The centre-of-mass target (a copy)."""

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass reference."""

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target (a copy), description order."""

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture reference, description order."""

    def set_posture_weights(self, weights: np.ndarray) -> None:
        """Per-joint multipliers of the posture weight (ones: the default)."""

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """Swing-foot reference (refused, or clamped, beyond the leg's reach)."""

    def set_foot_weight(self, leg: str, weight: float | None = None) -> None:
        """Weight of a swing foot's position task (``None``: the configured one)."""

    def com_position(self) -> np.ndarray:
        """Centre of mass at the last state."""

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity at the last state."""

    def foot_positions(self) -> np.ndarray:
        """The foot frames' positions (legs, 3) at the last state, in ``LEGS`` order."""

    def shoulder_position(self, leg: str) -> np.ndarray:
        """A leg's shoulder (fixed to the base) at the last state."""

    def normal_force(self, leg: str) -> float:
        """The normal force the last solved tick gave a foot."""
