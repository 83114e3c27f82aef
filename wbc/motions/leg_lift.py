"""Lifting one foot without a binary contact switch: shift, unload, raise, hold, and back."""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np

from wbc.controller.balance_controller import BalanceController
from wbc.controller.foot_reach import LEG_REACH_M
from wbc.core.errors import ConfigurationError, ReachabilityError
from wbc.core.min_jerk import min_jerk, min_jerk_reference
from wbc.core.validation import as_float, check_name
from wbc.model.description import LEGS
from wbc.model.support_polygon import SupportPolygon

#: Foot heights [m] (foot centre above the ground) the lift accepts.
MIN_HEIGHT_M, MAX_HEIGHT_M = 0.10, 0.50


def _foot(controller: BalanceController, leg: str) -> np.ndarray:
    """A foot's world position [m] at the controller's last state (a copy)."""
    return controller.foot_positions()[LEGS.index(leg)].copy()


class LiftPhase(enum.StrEnum):
    """Phases of a leg lift, in order."""

    SHIFTING = "shifting"            # centre of mass into the other three feet's triangle
    UNLOADING = "unloading"          # the schedule ramps the foot's force bound to zero
    RAISING = "raising"              # the released foot rises to its target
    HOLDING = "holding"              # the foot holds its target
    LOWERING = "lowering"            # the foot returns to its ground point
    RELOADING = "reloading"          # the schedule ramps the foot's force bound back up
    SHIFTING_BACK = "shifting_back"  # centre of mass back to the four-leg stance
    DONE = "done"


# The phases by plain name for the tick's tests: a member looked up on its enum class costs
# about 0.1 us in Python 3.11 (several times that on a loaded machine).
_SHIFTING, _UNLOADING, _RAISING, _HOLDING, _LOWERING, _RELOADING, _SHIFTING_BACK, _DONE = (
    LiftPhase)


@dataclass(frozen=True)
class LegLiftTiming:
    """Durations [s] of the phases, and how fast an interrupted lift unwinds."""

    shift_s: float = 1.0
    unload_s: float = 0.4
    raise_s: float = 1.5
    lower_s: float = 1.5
    reload_s: float = 0.4
    shift_back_s: float = 1.0
    #: Average foot speed [m/s] when an interrupted lift puts the foot down.
    unwind_speed_mps: float = 0.6
    #: Average foot speed [m/s] when the lift is interrupted because balance is being lost.
    urgent_speed_mps: float = 1.5
    #: Reload time [s] when balance is being lost: the landed foot must carry load now.
    urgent_reload_s: float = 0.05
    #: Reload and shift-back time [s] of an interrupted lift (they overlap).
    unwind_reload_s: float = 0.3
    unwind_shift_s: float = 0.5

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            as_float(name, value, low=0.0, low_inclusive=False)
        if self.unload_s < 0.3 or self.reload_s < 0.3:
            raise ConfigurationError(
                f"unload_s/reload_s: expected at least 0.3 s for a smooth force ramp, received "
                f"{self.unload_s:g} s and {self.reload_s:g} s"
            )


class LegLift:
    """Drives a :class:`BalanceController`'s references through one leg lift.

    Call :meth:`start` once, then :meth:`advance` every control tick before
    ``controller.step``; :meth:`request_lower` interrupts the lift at any phase and brings
    the robot back to four loaded feet in bounded time. Positions are world-frame [m].
    The foot is unloaded and reloaded by a ramp of its normal-force bound that the
    controller's contact schedule moves on every tick (asked for once a phase). The foot
    target is ``forward_m`` in front of the leg's shoulder and ``lateral_m`` outward, at
    ``height_m`` above the ground (the foot sphere's centre).
    """

    def __init__(self, controller: BalanceController, *, leg: str = "FR",
                 height_m: float = 0.40, hold_s: float = 2.0, forward_m: float = 0.20,
                 lateral_m: float = 0.0, shift_margin_m: float = 0.07,
                 touchdown_press_m: float = 0.001, timing: LegLiftTiming | None = None,
                 release_only: bool = False):
        """Args:
            controller: The whole-body controller whose references this drives.
            leg: The leg to raise (``FL``, ``FR``, ``RL`` or ``RR``).
            height_m: Target height of the foot centre above the ground [m].
            hold_s: Time to hold the foot at its target [s].
            forward_m: Target distance in front of the thigh joint [m].
            lateral_m: Target distance outward from the thigh joint [m].
            shift_margin_m: Margin [m] of the shifted centre of mass inside the triangle.
            touchdown_press_m: How far below its old ground point the foot is aimed [m], so
                that it surely touches before it is reloaded.
            timing: Phase durations.
            release_only: Stop once the foot is released (after unloading): the lift ends
                DONE with the leg in swing, its foot held where it was, for another motion
                (a joint trajectory) to take the leg over.
        """
        self.release_only = release_only
        self.controller = controller
        self.leg = check_name("leg", leg, LEGS)
        self.height_m = as_float("height_m", height_m, low=MIN_HEIGHT_M, high=MAX_HEIGHT_M)
        self.hold_s = as_float("hold_s", hold_s, low=0.0)
        self.forward_m = as_float("forward_m", forward_m, low=-0.1, high=0.3)
        self.lateral_m = as_float("lateral_m", lateral_m, low=-0.05, high=0.15)
        self.shift_margin_m = as_float("shift_margin_m", shift_margin_m, low=0.0, high=0.09)
        self.touchdown_press_m = as_float("touchdown_press_m", touchdown_press_m, low=0.0,
                                          high=0.01)
        self.timing = timing or LegLiftTiming()
        self.phase: LiftPhase | None = None
        self.interrupted = False
        self.urgent = False
        self._progress = 0.0
        # Position, velocity and acceleration rows of the references set every tick.
        self._com_motion = np.zeros((3, 3))
        self._foot_motion = np.zeros((3, 3))

    # ------------------------------------------------------------------ planning

    def start(self, now_s: float) -> None:
        """Plan the lift from the controller's last state and begin shifting.

        Raises:
            ReachabilityError: The foot target is out of the leg's reach; nothing changed.
            ConfigurationError: The leg is not in stance.
        """
        ctrl = self.controller
        stance = ctrl.schedule.stance_legs
        if self.leg not in stance or len(stance) < len(LEGS):
            raise ConfigurationError(
                f"leg: the lift needs all four feet in stance, stance now: {stance}")
        feet = {leg: _foot(ctrl, leg) for leg in LEGS}
        others = np.array([feet[leg][:2] for leg in LEGS if leg != self.leg])
        com0 = ctrl.com_target
        shifted = SupportPolygon(margin_m=self.shift_margin_m).closest_inside(others, com0)
        shift = np.array([shifted[0] - com0[0], shifted[1] - com0[1], 0.0])
        side = 1.0 if feet[self.leg][1] > ctrl.com_position()[1] else -1.0
        shoulder = ctrl.shoulder_position(self.leg) + shift
        target = np.array([shoulder[0] + self.forward_m, shoulder[1] + side * self.lateral_m,
                           self.height_m])
        distance = float(np.linalg.norm(target - shoulder))
        if distance > LEG_REACH_M:
            raise ReachabilityError(
                f"height_m: a foot target at {self.height_m:.3f} m is {distance:.3f} m from the "
                f"{self.leg} shoulder, beyond its reach of {LEG_REACH_M:.2f} m; valid heights: "
                f"[{MIN_HEIGHT_M:.2f}, {MAX_HEIGHT_M:.2f}] m"
            )
        self.com_home = com0
        self.com_shifted = com0 + shift
        self.foot_ground = feet[self.leg]
        self.foot_touch = self.foot_ground - np.array([0.0, 0.0, self.touchdown_press_m])
        self.foot_target = target
        self._foot_ref = self.foot_ground.copy()
        self._com_ref = com0.copy()
        self._enter(LiftPhase.SHIFTING, now_s, duration=self.timing.shift_s)
        self._from = self._com_ref.copy()
        self._to = self.com_shifted

    #: The foot target last set while holding (``None``: set it on the next hold tick).
    _held: list[float] | None = None

    def _enter(self, phase: LiftPhase, now_s: float, *, duration: float) -> None:
        self._held = None
        self.phase = phase
        self._t0 = now_s
        self._duration = max(duration, 1e-3)

    @property
    def nominal_duration_s(self) -> float:
        """Duration [s] of the whole lift when not interrupted."""
        t = self.timing
        if self.release_only:
            return t.shift_s + t.unload_s
        return (t.shift_s + t.unload_s + t.raise_s + self.hold_s + t.lower_s + t.reload_s
                + t.shift_back_s)

    # ------------------------------------------------------------------ ticking

    def advance(self, now_s: float) -> LiftPhase:
        """Set the controller's references for time ``now_s`` [s]; returns the phase."""
        if self.phase is None:
            raise ConfigurationError("LegLift.advance: call start(now_s) first")
        ctrl, t = self.controller, self.timing
        schedule = ctrl.schedule
        elapsed = now_s - self._t0
        done = elapsed >= self._duration
        phase = self.phase
        if phase is _SHIFTING or phase is _SHIFTING_BACK:
            self._track_com(elapsed)
            if done and phase is _SHIFTING:
                # Ramp from the load the foot carries, not from its (much higher) bound:
                # the bound only bites once it falls below the load.
                self._load_n = max(ctrl.normal_force(self.leg), schedule.min_normal_force_n)
                start = min(self._load_n, schedule.max_normal_force(self.leg))
                schedule.ramp_normal_force(self.leg, 0.0, t.unload_s, from_n=start)
                self._enter(LiftPhase.UNLOADING, now_s, duration=t.unload_s)
            elif done:
                self._enter(LiftPhase.DONE, now_s, duration=0.0)
        elif phase is _UNLOADING:
            if done:  # the schedule's ramp has brought the bound to zero
                schedule.set_swing(self.leg)
                # The foot rolled while the body shifted: start from where it is, and land
                # there, so that shifting back rolls it home.
                self._foot_ref = _foot(ctrl, self.leg)
                self.foot_touch = self._foot_ref - np.array([0.0, 0.0, self.touchdown_press_m])
                if self.release_only:
                    self._enter(LiftPhase.DONE, now_s, duration=0.0)
                else:
                    self._start_foot_motion(now_s, LiftPhase.RAISING, self.foot_target,
                                            t.raise_s)
        elif phase is _RAISING or phase is _LOWERING:
            self._track_foot(elapsed, lead_z=phase is _RAISING)
            if done and phase is _RAISING:
                self._enter(LiftPhase.HOLDING, now_s, duration=self.hold_s)
            elif done:
                schedule.set_stance(self.leg, max_normal_force_n=0.0)
                schedule.ramp_normal_force(self.leg, self._reload_to_n(), self._reload_s())
                self._enter(LiftPhase.RELOADING, now_s, duration=self._reload_s())
                self._from, self._to = self._com_ref.copy(), self.com_home
                self._shift_t0 = now_s
        elif phase is _HOLDING:
            held = self.foot_target.tolist()
            if held != self._held:
                ctrl.set_foot_target(self.leg, self.foot_target)  # at rest: set on change only
                self._held = held
            if done:
                self._start_foot_motion(now_s, LiftPhase.LOWERING, self.foot_touch, t.lower_s)
        elif phase is _RELOADING:
            # The schedule ramps up to the load the foot carried before the lift; at the
            # end the bound is released.
            if done:
                schedule.set_max_normal_force(self.leg, schedule.full_normal_force_n)
            if self.interrupted:  # an unwind shifts back while it reloads
                self._track_com(now_s - self._shift_t0, duration=t.unwind_shift_s)
            if done and self.interrupted:
                # Carry on with the shift already under way.
                self._enter(LiftPhase.SHIFTING_BACK, self._shift_t0, duration=t.unwind_shift_s)
            elif done:
                self._from, self._to = self._com_ref.copy(), self.com_home
                self._enter(LiftPhase.SHIFTING_BACK, now_s, duration=t.shift_back_s)
        self._update_progress(now_s)
        return self.phase

    def _track_com(self, elapsed: float, duration: float | None = None) -> None:
        duration = self._duration if duration is None else duration
        motion = self._com_motion
        min_jerk_reference(motion, self._from, self._to, elapsed, duration, 0.0, 1.0)
        self._com_ref = motion[0]
        self.controller.set_com_target(motion[0], motion[1], motion[2])

    def _start_foot_motion(self, now_s: float, phase: LiftPhase, end: np.ndarray,
                           nominal_s: float) -> None:
        start = self._foot_ref.copy()
        if self.interrupted:
            distance = float(np.linalg.norm(end - start))
            speed, shortest = ((self.timing.urgent_speed_mps, 0.15) if self.urgent
                               else (self.timing.unwind_speed_mps, 0.3))
            nominal_s = float(np.clip(distance / speed, shortest, nominal_s))
        self._from, self._to = start, np.array(end, dtype=float)
        self._enter(phase, now_s, duration=nominal_s)

    def _track_foot(self, elapsed: float, *, lead_z: bool) -> None:
        """Minimum-jerk foot path; the vertical motion leads when rising, lags when lowering.

        Rising, the horizontal motion starts after a quarter of the time (the foot leaves
        the ground vertically); lowering, it ends a quarter early (the foot lands vertically).
        """
        motion = self._foot_motion
        min_jerk_reference(motion, self._from, self._to, elapsed, self._duration,
                           0.25 if lead_z else 0.0, 0.75)
        self._foot_ref = motion[0]
        self.controller.set_foot_target(self.leg, motion[0], motion[1], motion[2],
                                        clamp_to_reach=self.interrupted)

    @classmethod
    def put_down(cls, controller: BalanceController, leg: str, ground_point: np.ndarray,
                 com_home: np.ndarray, now_s: float) -> LegLift:
        """A lift that only puts a swinging foot down: lower, reload, shift back.

        For a foot left in the air (by a joint trajectory, an aborted goal): it is lowered
        from where it is to ``ground_point`` [m] and reloaded, and the centre of mass goes
        to ``com_home`` [m].
        """
        lift = cls(controller, leg=leg, height_m=MIN_HEIGHT_M, hold_s=0.0)
        if controller.schedule.is_stance(leg):
            raise ConfigurationError(f"leg: {leg} is already in stance; nothing to put down")
        lift.com_home = np.array(com_home, dtype=float)
        lift.foot_ground = np.array(ground_point, dtype=float)
        lift.foot_touch = lift.foot_ground - np.array([0.0, 0.0, lift.touchdown_press_m])
        lift.foot_target = _foot(controller, leg)
        lift._foot_ref = lift.foot_target.copy()
        lift._com_ref = controller.com_target
        lift._enter(LiftPhase.HOLDING, now_s, duration=1.0)
        lift.request_lower(now_s)
        return lift

    # ------------------------------------------------------------------ interruption

    def request_lower(self, now_s: float, *, urgent: bool = False) -> None:
        """Interrupt: put the foot down and return to four loaded feet, from any phase.

        The foot is lowered at ``unwind_speed_mps`` (``urgent_speed_mps`` when ``urgent``,
        e.g. because balance is being lost), then reloaded in ``unwind_reload_s`` while the
        centre of mass shifts back in ``unwind_shift_s``.
        """
        self.urgent = self.urgent or urgent
        if self.phase is None or self.interrupted or self.phase is LiftPhase.DONE:
            self.interrupted = True
            return
        self.interrupted = True
        t, ctrl = self.timing, self.controller
        self._progress_at_interrupt = self._progress
        self._interrupt_s = now_s
        if self.phase is LiftPhase.SHIFTING:
            self._from, self._to = self._com_ref.copy(), self.com_home
            self._enter(LiftPhase.SHIFTING_BACK, now_s, duration=t.unwind_shift_s)
        elif self.phase in (LiftPhase.UNLOADING, LiftPhase.RELOADING):
            # Reload from the current bound at the unwind pace, shifting back meanwhile: the
            # reload's ramp taken up where it reaches the current bound.
            schedule = ctrl.schedule
            reload_to, reload_s = self._reload_to_n(), self._reload_s()
            s0 = min(1.0, schedule.max_normal_force(self.leg) / reload_to)
            already_s = self._inverse_ramp(s0) * reload_s
            schedule.ramp_normal_force(self.leg, reload_to, reload_s, from_n=0.0,
                                       elapsed_s=already_s)
            self._enter(LiftPhase.RELOADING, now_s - already_s, duration=reload_s)
            self._from, self._to = self._com_ref.copy(), self.com_home
            self._shift_t0 = now_s
        elif self.phase in (LiftPhase.RAISING, LiftPhase.HOLDING, LiftPhase.LOWERING):
            self._start_foot_motion(now_s, LiftPhase.LOWERING, self.foot_touch, t.lower_s)
        # SHIFTING_BACK already has four loaded feet and ends within shift_back_s.

    def _reload_to_n(self) -> float:
        """The bound the reload ramps to: the foot's load before the lift, with room to spare."""
        ctrl, schedule = self.controller, self.controller.schedule
        load = getattr(self, "_load_n", ctrl.description.total_mass * 9.81 / len(LEGS))
        return min(schedule.full_normal_force_n, 1.5 * load + 2.0 * schedule.min_normal_force_n)

    def _reload_s(self) -> float:
        t = self.timing
        if self.urgent:
            return t.urgent_reload_s
        return t.unwind_reload_s if self.interrupted else t.reload_s

    @staticmethod
    def _inverse_ramp(s: float) -> float:
        """The time fraction at which the minimum-jerk ramp reaches ``s`` (bisection)."""
        low, high = 0.0, 1.0
        for _ in range(40):
            mid = 0.5 * (low + high)
            if min_jerk(mid)[0] < s:
                low = mid
            else:
                high = mid
        return 0.5 * (low + high)

    # ------------------------------------------------------------------ progress

    #: Each phase's start and duration [s] on the uninterrupted plan (``None``: the whole).
    _phase_offsets: dict[LiftPhase | None, tuple[float, float]] | None = None

    def _plan_phase_offsets(self) -> dict[LiftPhase | None, tuple[float, float]]:
        t = self.timing
        order = [(LiftPhase.SHIFTING, t.shift_s), (LiftPhase.UNLOADING, t.unload_s),
                 (LiftPhase.RAISING, t.raise_s), (LiftPhase.HOLDING, self.hold_s),
                 (LiftPhase.LOWERING, t.lower_s), (LiftPhase.RELOADING, t.reload_s),
                 (LiftPhase.SHIFTING_BACK, t.shift_back_s)]
        offsets: dict[LiftPhase | None, tuple[float, float]] = {}
        start = 0.0
        for phase, duration in order:
            offsets[phase] = (start, duration)
            start += duration
        offsets[None] = (self.nominal_duration_s, 0.0)
        return offsets

    @property
    def progress(self) -> float:
        """Fraction of the lift done, 0 to 1, never decreasing (also across an interrupt)."""
        return self._progress

    def _update_progress(self, now_s: float) -> None:
        if self.phase is _DONE:
            self._progress = 1.0
            return
        if self.interrupted:
            bound = self.timing.lower_s + self.timing.unwind_reload_s + self.timing.unwind_shift_s
            fraction = min((now_s - self._interrupt_s) / bound, 0.99)
            start = getattr(self, "_progress_at_interrupt", self._progress)
            estimate = start + (1.0 - start) * fraction
        else:
            offsets = self._phase_offsets
            if offsets is None:
                offsets = self._phase_offsets = self._plan_phase_offsets()
            start, duration = offsets[self.phase]
            done = start + min(max(now_s - self._t0, 0.0), duration)
            estimate = min(done / offsets[None][0], 0.999)
        self._progress = max(self._progress, estimate)
