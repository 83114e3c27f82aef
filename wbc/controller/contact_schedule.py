"""Which feet stand, how much each may carry, and the ramps that unload and reload them."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numba import types

from wbc.controller.controller_config import ContactSettings
from wbc.core.errors import ConfigurationError
from wbc.core.min_jerk import min_jerk
from wbc.core.validation import as_float, check_name

_WORDS = {2: "two", 3: "three", 4: "four", 5: "five", 6: "six"}
# min_jerk's compiled overload called directly: a ramp's every tick skips the dispatcher's
# typing of its argument (about half of a call's cost).
_MIN_JERK = min_jerk.overloads[(types.float64,)].entry_point


@dataclass
class _Ramp:
    """A minimum-jerk ramp of one foot's bound, ``start_n`` to ``end_n`` over ``duration_s``."""

    start_n: float
    end_n: float
    duration_s: float
    elapsed_s: float
    #: Controller ticks seen since the ramp was asked for (the first tick uses ``elapsed_s``).
    ticks: int = 0

    def value(self, elapsed_s: float) -> float:
        s = _MIN_JERK(elapsed_s / self.duration_s)[0]
        return self.start_n + (self.end_n - self.start_n) * s


class ContactSchedule:
    """The contact schedule of a legged robot: each foot in stance or in swing, the upper
    bound of each stance foot's normal force [N], and ramps of those bounds over time.

    A foot is unloaded before it is lifted, and reloaded after it lands, by ramping its
    bound (:meth:`ramp_normal_force`) rather than by a binary contact switch: the
    controller advances the ramps once per tick (:meth:`advance`) and its QP reads the
    bounds where they are (:attr:`bounds`). Who drives the schedule (a leg lift, a
    behaviour) asks for a ramp once and goes on with its own timing.

    The controller that owns the schedule is told of every change to a foot (``listener``).
    Legs are named as the controller's contacts (``FL, FR, RL, RR`` on a GO2).
    """

    def __init__(self, contacts: Sequence[str], settings: ContactSettings, *,
                 control_period_s: float, min_stance: int = 3,
                 listener: Callable[[str], None] | None = None):
        """Args:
            contacts: The feet, in the controller's order.
            settings: The minimum and full normal forces (:class:`ContactSettings`).
            control_period_s: How much a ramp advances each tick [s].
            min_stance: Fewest feet that must stay in stance.
            listener: Called with a foot's name after its mode or its bound changed (by a
                call, or by a ramp in :meth:`advance`).
        """
        self.contacts = tuple(contacts)
        self.settings = settings
        self.control_period_s = as_float("control_period_s", control_period_s, low=0.0,
                                         low_inclusive=False)
        self.min_stance = min_stance
        self._listener = listener
        self._stance = np.ones(len(self.contacts), dtype=bool)
        self._bounds = np.full(len(self.contacts), settings.max_normal_force_n)
        self._ramps: dict[int, _Ramp] = {}
        self._mode_changes = 0
        self._support_changes = 0

    def set_listener(self, listener: Callable[[str], None] | None) -> None:
        """Who is told of each change to a foot (the controller that owns the schedule)."""
        self._listener = listener

    # ------------------------------------------------------------------ reading

    @property
    def bounds(self) -> np.ndarray:
        """Each foot's normal-force bound [N] (contacts,), 0 in swing: the array itself,
        read-only, updated in place (a QP's friction cones read it every tick)."""
        view = self._bounds.view()
        view.flags.writeable = False
        return view

    @property
    def stance(self) -> list[bool]:
        """Whether each foot is in stance, in the contacts' order (a new list)."""
        return self._stance.tolist()

    @property
    def stance_legs(self) -> list[str]:
        """Feet currently in stance."""
        return [c for c, s in zip(self.contacts, self._stance) if s]

    def is_stance(self, leg: str) -> bool:
        """Whether a foot is in stance."""
        return bool(self._stance[self._index(leg)])

    def support_legs(self) -> list[str]:
        """Stance feet that are fully loaded: the corners of the support polygon."""
        full = self.settings.max_normal_force_n
        # Python's bools and floats: iterating the arrays made a NumPy scalar of each entry
        # (about 1.5 us a call, and the balance watch calls it every tick).
        return [c for c, s, b in zip(self.contacts, self._stance.tolist(),
                                     self._bounds.tolist()) if s and b >= full]

    def normal_force_bounds(self, out: np.ndarray) -> np.ndarray:
        """Each foot's normal-force bound [N] into ``out`` (contacts,), 0 in swing: what a
        state estimator reads as the contact schedule (:class:`wbc.StateEstimator`)."""
        out[:] = self._bounds
        return out

    def max_normal_force(self, leg: str) -> float:
        """Current upper bound [N] of a foot's normal force (0 in swing)."""
        return float(self._bounds[self._index(leg)])

    @property
    def min_normal_force_n(self) -> float:
        """The minimum normal force [N] of a loaded stance foot."""
        return self.settings.min_normal_force_n

    @property
    def full_normal_force_n(self) -> float:
        """The normal-force bound [N] of a fully loaded stance foot."""
        return self.settings.max_normal_force_n

    @property
    def mode_changes(self) -> int:
        """How many times a foot's mode may have changed (stance or swing; also counts a call
        that set a mode it already had): equal counts, no change between them. What the
        controller compares to skip re-reading the modes when only a bound moved."""
        return self._mode_changes

    @property
    def support_changes(self) -> int:
        """How many times :meth:`support_legs` may have changed (a mode set, a bound set, or a
        ramped bound crossing the full bound): equal counts, the same support feet."""
        return self._support_changes

    def is_ramping(self, leg: str) -> bool:
        """Whether a ramp of the foot's bound is under way."""
        return self._index(leg) in self._ramps

    # ------------------------------------------------------------------ changing

    def reset(self) -> None:
        """Every foot in stance at the full bound, no ramps (the listener is told)."""
        self._ramps.clear()
        self._stance[:] = True
        self._bounds[:] = self.settings.max_normal_force_n
        self._mode_changes += 1
        self._support_changes += 1
        for leg in self.contacts:
            self._changed(leg)

    def set_max_normal_force(self, leg: str, value_n: float) -> None:
        """Upper bound [N] of a stance foot's normal force, now (ends a ramp of that foot).

        Raises:
            ConfigurationError: The foot is in swing, or the value is outside ``[0, full]``.
        """
        i = self._index(leg)
        value = self._checked_force(leg, value_n)
        if not self._stance[i]:
            raise ConfigurationError(
                f"leg: {leg} is in swing; call set_stance({leg!r}) before loading it")
        self._ramps.pop(i, None)
        self._bounds[i] = value
        self._support_changes += 1
        self._changed(leg)

    def ramp_normal_force(self, leg: str, to_n: float, duration_s: float, *,
                          from_n: float | None = None, elapsed_s: float = 0.0) -> None:
        """Ramp a stance foot's bound from ``from_n`` (its bound now when ``None``) to
        ``to_n`` [N] over ``duration_s`` [s] (minimum jerk: no jump in the bound's rate).

        The bound takes the ramp's value at ``elapsed_s`` now (the first tick uses it),
        then each tick advances it by the control period; at the end it stays at ``to_n``.
        ``elapsed_s`` continues a ramp already under way (a reload resumed from where an
        unload stopped). A new ramp, :meth:`set_max_normal_force` or a change of mode ends
        the foot's ramp.

        Raises:
            ConfigurationError: The foot is in swing, a force outside ``[0, full]``, or a
                duration that is not positive (each names the argument).
        """
        i = self._index(leg)
        if not self._stance[i]:
            raise ConfigurationError(
                f"leg: {leg} is in swing; call set_stance({leg!r}) before ramping its bound")
        start = float(self._bounds[i]) if from_n is None else self._checked_force(leg, from_n)
        end = self._checked_force(leg, to_n)
        duration = as_float("duration_s", duration_s, low=0.0, low_inclusive=False)
        elapsed = as_float("elapsed_s", elapsed_s, low=0.0)
        ramp = _Ramp(start, end, duration, elapsed)
        self._ramps[i] = ramp
        self._bounds[i] = ramp.value(elapsed)
        self._support_changes += 1
        self._changed(leg)

    def set_swing(self, leg: str) -> None:
        """Release a foot: no contact force (its bound is 0), its position task takes over.

        Raises:
            ConfigurationError: Fewer than ``min_stance`` feet would stay in stance.
        """
        i = self._index(leg)
        if self._stance[i] and int(self._stance.sum()) <= self.min_stance:
            raise ConfigurationError(
                f"leg: cannot release {leg}: at least "
                f"{_WORDS.get(self.min_stance, self.min_stance)} feet must stay in stance "
                f"(stance now: {', '.join(self.stance_legs)})")
        self._ramps.pop(i, None)
        self._stance[i] = False
        self._bounds[i] = 0.0
        self._mode_changes += 1
        self._support_changes += 1
        self._changed(leg)

    def set_stance(self, leg: str, *, max_normal_force_n: float = 0.0) -> None:
        """Make a foot a stance contact with the given maximum normal force [N].

        Start at zero and ramp it up (:meth:`ramp_normal_force`) for a smooth touch-down.
        """
        i = self._index(leg)
        value = self._checked_force(leg, max_normal_force_n)
        self._ramps.pop(i, None)
        self._stance[i] = True
        self._bounds[i] = value
        self._mode_changes += 1
        self._support_changes += 1
        self._changed(leg)

    def advance(self) -> None:
        """Move every ramp on by one tick (the controller calls it once per tick, before
        it reads the bounds): a ramp asked for since the last tick is used as it was."""
        ramps = self._ramps
        if not ramps:
            return
        dt, bounds = self.control_period_s, self._bounds
        full = self.settings.max_normal_force_n
        for i, ramp in list(ramps.items()):
            ramp.ticks += 1
            if ramp.ticks == 1:
                continue
            elapsed = ramp.elapsed_s + (ramp.ticks - 1) * dt
            if elapsed >= ramp.duration_s:
                value = ramp.end_n
                del ramps[i]
            else:
                value = ramp.value(elapsed)
            if (bounds.item(i) >= full) != (value >= full):  # a support foot more or less
                self._support_changes += 1
            bounds[i] = value
            self._changed(self.contacts[i])

    # ------------------------------------------------------------------ helpers

    def _index(self, leg: str) -> int:
        check_name("leg", leg, self.contacts)
        return self.contacts.index(leg)

    def _checked_force(self, leg: str, value_n: float) -> float:
        return as_float(f"{leg} max_normal_force_n", value_n, low=0.0,
                        high=self.settings.max_normal_force_n)

    def _changed(self, leg: str) -> None:
        if self._listener is not None:
            self._listener(leg)
