"""A periodic gait: its parameters, the velocity limits, and each leg's phase in the cycle."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, check_name, is_finite_real
from wbc.model.description import LEGS

#: Each gait's phase offset of every leg, as a fraction of the cycle (``LEGS`` order).
GAIT_OFFSETS: dict[str, tuple[float, ...]] = {
    # Diagonal pairs in antiphase: FL with RR, FR with RL.
    "trot": (0.0, 0.5, 0.5, 0.0),
    # A lateral-sequence walk: RL, FL, RR, FR a quarter cycle apart (one foot up at a time
    # when the duty factor is at least 0.75).
    "walk": (0.25, 0.75, 0.0, 0.5),
}


@dataclass(frozen=True)
class GaitParameters:
    """The gait's shape: which legs move together, its timing and its steps.

    Attributes:
        name: ``trot`` (diagonal pairs) or ``walk`` (one leg at a time, for slow speeds).
        period_s: One gait cycle [s].
        duty_factor: Share of the cycle a foot is in stance (``> 0.5`` for a trot: both pairs
            stand together at each exchange, while one pair's force ramps down and the
            other's up).
        swing_height_m: Apex of the swing foot above its lift-off height [m].
        transfer_s: Duration [s] of each force ramp: the unload before a lift-off and the
            reload after a touch-down.
        touchdown_press_m: How far below the ground the swing foot is aimed [m], so that it
            surely touches at the end of the swing.
    """

    name: str = "trot"
    period_s: float = 0.5
    duty_factor: float = 0.55
    swing_height_m: float = 0.08
    transfer_s: float = 0.04
    touchdown_press_m: float = 0.003

    def __post_init__(self) -> None:
        check_name("gait", self.name, GAIT_OFFSETS)
        as_float("period_s", self.period_s, low=0.2, high=2.0)
        low_duty = 0.75 if self.name == "walk" else 0.5
        as_float("duty_factor", self.duty_factor, low=low_duty, high=0.9,
                 low_inclusive=self.name == "walk")
        as_float("swing_height_m", self.swing_height_m, low=0.02, high=0.2)
        as_float("touchdown_press_m", self.touchdown_press_m, low=0.0, high=0.01)
        as_float("transfer_s", self.transfer_s, low=0.005, low_inclusive=True)
        if 2.0 * self.transfer_s > self.stance_s:
            raise ConfigurationError(
                f"transfer_s: expected at most half the stance time "
                f"({self.stance_s / 2:g} s = period_s {self.period_s:g} s x duty_factor "
                f"{self.duty_factor:g} / 2): the reload and the unload must both fit in a "
                f"stance; received {self.transfer_s:g} s")

    @property
    def stance_s(self) -> float:
        """A foot's stance time [s] in one cycle."""
        return self.period_s * self.duty_factor

    @property
    def swing_s(self) -> float:
        """A foot's swing time [s] in one cycle."""
        return self.period_s * (1.0 - self.duty_factor)

    @property
    def offsets(self) -> tuple[float, ...]:
        """Each leg's phase offset (``LEGS`` order), a fraction of the cycle."""
        return GAIT_OFFSETS[self.name]


@dataclass(frozen=True)
class VelocityLimits:
    """The largest velocity a command may ask for, each axis symmetric about zero.

    Attributes:
        forward_mps: Forward speed [m/s] (base heading).
        lateral_mps: Sideways speed [m/s].
        yaw_rate_radps: Turning rate [rad/s].
    """

    forward_mps: float = 1.0
    lateral_mps: float = 0.4
    yaw_rate_radps: float = 1.2

    def __post_init__(self) -> None:
        as_float("forward_mps", self.forward_mps, low=0.0, high=2.0)
        as_float("lateral_mps", self.lateral_mps, low=0.0, high=1.0)
        as_float("yaw_rate_radps", self.yaw_rate_radps, low=0.0, high=3.0)

    def problem(self, forward_mps: Any, lateral_mps: Any, yaw_rate_radps: Any) -> str:
        """Why a command is not valid ('' when it is): the first field beyond its limit or
        not a finite number, the value received and the valid range with its unit."""
        for name, value, limit, unit in (
                ("forward_mps", forward_mps, self.forward_mps, "m/s"),
                ("lateral_mps", lateral_mps, self.lateral_mps, "m/s"),
                ("yaw_rate_radps", yaw_rate_radps, self.yaw_rate_radps, "rad/s")):
            if isinstance(value, bool) or not is_finite_real(value) or abs(value) > limit + 1e-12:
                return (f"{name}: expected a velocity in [{-limit:g}, {limit:g}] {unit}, "
                        f"received {value!r}")
        return ""

    def check(self, forward_mps: float, lateral_mps: float,
              yaw_rate_radps: float) -> tuple[float, float, float]:
        """The command as floats, each within its limit.

        Raises:
            ConfigurationError: A value beyond its limit or not a finite number (the field,
                the value and the valid range named, as :meth:`problem` says it).
        """
        problem = self.problem(forward_mps, lateral_mps, yaw_rate_radps)
        if problem:
            raise ConfigurationError(problem)
        return float(forward_mps), float(lateral_mps), float(yaw_rate_radps)


class GaitClock:
    """Where each leg is in the gait cycle at a gait time [s].

    Each leg's cycle starts at touch-down: local phase ``0`` to ``duty_factor`` is stance,
    ``duty_factor`` to ``1`` swing. Its cycle number counts touch-downs, so a lift-off or a
    touch-down is an event of one numbered cycle, never confused across the wrap.
    """

    def __init__(self, gait: GaitParameters):
        self.gait = gait

    def cycle(self, leg: str, time_s: float) -> tuple[int, float]:
        """The leg's cycle number and its phase in ``[0, 1)`` at gait time ``time_s`` [s]."""
        position = time_s / self.gait.period_s - self.gait.offsets[LEGS.index(leg)]
        number = math.floor(position)
        return number, position - number

    def in_swing(self, leg: str, time_s: float) -> bool:
        """Whether the gait has the leg in the air at ``time_s`` [s]."""
        return self.cycle(leg, time_s)[1] >= self.gait.duty_factor

    def swing_progress(self, leg: str, time_s: float) -> float:
        """Fraction of the swing done at ``time_s`` [s] (0 outside a swing)."""
        phase = self.cycle(leg, time_s)[1]
        duty = self.gait.duty_factor
        return (phase - duty) / (1.0 - duty) if phase >= duty else 0.0

    def time_to_liftoff(self, leg: str, time_s: float) -> float:
        """Time [s] from ``time_s`` to the leg's next lift-off (0 when in the air)."""
        phase = self.cycle(leg, time_s)[1]
        duty = self.gait.duty_factor
        return 0.0 if phase >= duty else (duty - phase) * self.gait.period_s

    def time_to_touchdown(self, leg: str, time_s: float) -> float:
        """Time [s] from ``time_s`` to the end of the leg's swing (or of its next one)."""
        return (1.0 - self.cycle(leg, time_s)[1]) * self.gait.period_s
