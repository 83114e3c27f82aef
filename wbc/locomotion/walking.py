"""Walking on velocity commands: a periodic gait on the whole-body controller's contact
schedule, swing feet on smooth paths to footholds from the commanded and measured velocity."""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from wbc.controller.balance_controller import BalanceController
from wbc.controller.foot_reach import LEG_REACH_M
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.core.min_jerk import min_jerk
from wbc.locomotion.command_envelope import HIP_ACCEL, CommandEnvelope
from wbc.locomotion.foothold_planner import FootholdPlanner, yaw_rotation
from wbc.locomotion.gait import GaitClock, GaitParameters, VelocityLimits
from wbc.locomotion.walk_phase import LegState as _Leg
from wbc.locomotion.walk_phase import WalkPhase
from wbc.locomotion.walking_groups import (
    EV_LATE,
    EV_LIFT_OFF,
    EV_REFUSED,
    EV_RELOAD,
    EV_TOUCH_DOWN,
    EV_UNLOAD,
    PARAMS_DTYPE,
    STATE_DTYPE,
    TICK_COM_REFUSED,
    Measured,
    Targets,
    address_record,
)
from wbc.locomotion.walking_kernels import (
    MEASURE_SIGNATURE,
    SWING_SIGNATURE,
    TICK_SIGNATURE,
    walking_measure,
    walking_swing,
    walking_tick,
)
from wbc.locomotion.walking_tuning import (
    COM_WEIGHT,
    LINEAR_ACCEL,
    SETTLE_S,
    STOP_ACCEL,
    SWING_KD,
    VELOCITY_LEAD_RAD_S,
    YAW_ACCEL,
)
from wbc.model.description import LEGS

# The phases by plain name (an enum member looked up on its class is slow in Python 3.11).
_DONE, _STOPPING = WalkPhase.DONE, WalkPhase.STOPPING
_IN_THE_AIR = (_Leg.SWING, _Leg.LATE)


class Walking:
    """Drives a :class:`WholeBodyController` through a gait on velocity commands.

    A motion like :class:`wbc.LegLift`: :meth:`start` once, :meth:`set_velocity` any time,
    :meth:`advance` every control tick before ``controller.step``; :meth:`request_stop` ends
    on four loaded feet. The feet are unloaded before a lift-off and reloaded after a
    touch-down by the contact schedule's force ramps (``transfer_s`` each). Positions are
    world-frame [m]; velocities in the heading frame (x forward, y left).

    The gait's state machine (unload, lift-off, touch-down, late, the stop) is here; what is
    computed every tick (measure, body references, footholds, swing paths, landing tests) is
    one compiled call (:mod:`wbc.locomotion.walking_kernels`) on the walk's state record.
    """

    def __init__(self, controller: BalanceController, *, gait: GaitParameters | None = None,
                 limits: VelocityLimits | None = None):
        """Args:
            controller: The whole-body controller (its schedule, CoM, base and foot tasks).
            gait: The gait (a trot by default).
            limits: What :meth:`set_velocity` accepts.

        Raises:
            ConfigurationError: A controller that is not a :class:`WholeBodyController`.
        """
        if not isinstance(controller, WholeBodyController):
            raise ConfigurationError(
                f"controller: walking needs a WholeBodyController (its base and foot tasks), "
                f"received {type(controller).__name__}")
        self.controller = controller
        self.gait = gait or GaitParameters()
        self.limits = limits or VelocityLimits()
        self.clock = GaitClock(self.gait)
        self.phase: WalkPhase | None = None
        self._params = np.zeros(1, PARAMS_DTYPE)
        self._state = np.zeros(1, STATE_DTYPE)
        state = self._state[0]  # its fields as views, written by the kernel and here
        #: Commanded velocity: forward, lateral [m/s], yaw rate [rad/s] (heading frame),
        #: as it follows the last command at bounded accelerations.
        self.commanded_velocity: np.ndarray = state["commanded_velocity"]
        self.target_velocity = np.zeros(3)
        self.measured_velocity: np.ndarray = state["measured_velocity"]
        self._legs = dict.fromkeys(LEGS, _Leg.STANCE)
        self._swing_legs: tuple[str, ...] = ()
        self._mode, self._lifted, self._cycle = state["mode"], state["lifted"], state["cycle"]
        self._events, self._starts, self._ground = state["events"], state["starts"], state["ground"]
        self._footholds, self._path = state["footholds"], state["path"]
        self._com_ref, self._com_velocity = state["com_ref"], state["com_velocity"]
        self._following = True  # the commanded velocity may not be the scaled target yet

    def set_velocity(self, forward_mps: float, lateral_mps: float,
                     yaw_rate_radps: float) -> None:
        """The velocity to walk at (heading frame); ignored once stopping.

        Raises:
            ConfigurationError: A value beyond :attr:`limits` (the field named).
        """
        checked = self.limits.check(forward_mps, lateral_mps, yaw_rate_radps)
        if self.phase in (WalkPhase.STOPPING, WalkPhase.DONE):
            return
        self.target_velocity[:] = checked
        self._following = True

    def start(self, now_s: float) -> None:
        """Begin from four feet in stance at time ``now_s`` [s].

        Raises:
            ConfigurationError: Not every foot in stance.
        """
        ctrl = self.controller
        if len(ctrl.schedule.stance_legs) < len(LEGS):
            raise ConfigurationError(f"walking needs all four feet in stance, stance now: "
                                     f"{ctrl.schedule.stance_legs}")
        com = ctrl.com_position()
        yaw = self._yaw()
        feet = ctrl.foot_positions()
        heading = yaw_rotation(-yaw)
        offsets = {leg: heading @ (feet[i, :2] - com[:2]) for i, leg in enumerate(LEGS)}
        # Centre the stance on the CoM, so that each diagonal's midpoint lies under it.
        mean = np.mean(list(offsets.values()), axis=0)
        offsets = {leg: o - mean for leg, o in offsets.items()}
        ground = float(np.mean(feet[:, 2]))
        height = com[2] - ground
        shoulder_height = float(np.mean([ctrl.shoulder_position(leg)[2] for leg in LEGS]))
        reach = math.sqrt(max(LEG_REACH_M ** 2 - (shoulder_height - ground) ** 2, 0.01))
        self.planner = FootholdPlanner(offsets, com_height_m=height,
                                       max_step_m=min(0.2, 0.8 * reach))
        #: What the trot can follow: the command scaled to the legs' reach, hips' accelerations.
        self.envelope = CommandEnvelope([offsets[leg] for leg in LEGS], stance_s=self.gait.stance_s,
                                        max_step_m=self.planner.max_step_m,
                                        turn_gain_s=0.5 * self.planner.feedback_gain)
        self._com_ref[:] = com
        # Where the CoM stands over the feet (from their centroid, heading frame at _yaw0).
        self._home, self._yaw0 = com[:2] - feet[:, :2].mean(axis=0), yaw
        self._settle_s: float | None = None
        #: The base height [m] above the ground that walking holds: the height at the start.
        self.base_height_m = float(ctrl.kinematics.base_position[2]) - ground
        self._min_stance = ctrl.schedule.min_stance
        ctrl.schedule.min_stance = 2
        self._com_weight = ctrl.com_task.weight
        self._shaping = shaping = ctrl.motor.settings
        ctrl.motor.retune(replace(
            shaping, swing_kd=max(SWING_KD, shaping.swing_kd),
            reference_velocity_bound_rad_s=max(VELOCITY_LEAD_RAD_S,
                                               shaping.reference_velocity_bound_rad_s)))
        ctrl.com_task.set_weight(max(COM_WEIGHT, self._com_weight))
        ctrl.base_task.rotation[:] = np.eye(3)  # level; each tick then sets its yaw block
        gait = self.gait
        # The first lift-off one transfer (and a tick) from now: the leg of offset 0.5 (FR
        # in a trot), or the first of the walk's sequence.
        first = max(gait.offsets)
        self._start_records(
            gait_time_s=((first + gait.duty_factor) * gait.period_s - gait.transfer_s
                         - 2 * ctrl.control_period_s),
            yaw=yaw, feet=feet, com_height_m=float(com[2]) - ground)
        self._last_s = now_s
        self.phase = WalkPhase.STARTING

    def _start_records(self, *, gait_time_s: float, yaw: float, feet: np.ndarray,
                       com_height_m: float) -> None:
        """The kernel's parameters and the state it starts from; its calls bound."""
        ctrl, gait, planner = self.controller, self.gait, self.planner
        params = self._params[0]
        for name, value in (
                ("period_s", gait.period_s), ("duty_factor", gait.duty_factor),
                ("swing_s", gait.swing_s), ("stance_s", gait.stance_s),
                ("swing_height_m", gait.swing_height_m),
                ("touchdown_press_m", gait.touchdown_press_m),
                # The share of the cycle at which a stance leg's unloading may start.
                ("window", gait.duty_factor - gait.transfer_s / gait.period_s),
                ("feedback_gain", planner.feedback_gain), ("max_step_m", planner.max_step_m),
                ("com_height_m", com_height_m), ("base_height_m", self.base_height_m),
                ("control_period_s", ctrl.control_period_s), ("offsets", gait.offsets),
                ("nominal", [planner.offsets[leg] for leg in LEGS]),
                ("shoulder", [ctrl.reach.shoulder_in_base(leg) for leg in LEGS])):
            params[name] = value
        state = self._state[0]
        state["gait_time_s"], state["trim"], state["yaw_ref"] = gait_time_s, 0.0, yaw
        state["planted"] = 0  # a stop has ended the stepping (1)
        self._ground[:] = feet[:, 2]
        self._lifted[:] = -10
        kin = ctrl.kinematics
        measured = Measured(kin.com_position, kin.com_velocity, kin.base_rotation,
                            kin.base_position, kin.v, kin.frame_position)
        feet_tasks = tuple(ctrl.foot_tasks[leg].reference for leg in LEGS)
        targets = Targets(ctrl.com_task.reference, ctrl.base_task.rotation,
                          ctrl.base_task.reference, feet_tasks)
        # The groups stay referenced here: the kernel reads and writes at their addresses.
        self._groups = (measured, targets)
        addresses = address_record(measured, targets)
        self._tick = _bound(walking_tick, TICK_SIGNATURE, addresses, self._params, self._state)
        self._swing_leg = _bound(walking_swing, SWING_SIGNATURE, addresses, self._params,
                                 self._state)
        self._measure = _bound(walking_measure, MEASURE_SIGNATURE, addresses, self._state)

    def request_stop(self, now_s: float) -> None:
        """Zero velocity: the walk takes its last steps and ends on four loaded feet."""
        if self.phase in (None, WalkPhase.DONE, WalkPhase.STOPPING):
            return
        self.target_velocity[:] = 0.0
        self._following = True
        self._state[0]["stop_s"] = now_s
        self.phase = WalkPhase.STOPPING

    @property
    def gait_phase(self) -> float:
        """Position in the gait cycle, ``[0, 1)``."""
        return (self.gait_time_s / self.gait.period_s) % 1.0

    @property
    def gait_time_s(self) -> float:
        """The gait clock [s] (held while a foot is late)."""
        return float(self._state[0]["gait_time_s"])

    @property
    def distance_m(self) -> float:
        """Path length [m] the CoM travelled (horizontally) since the start."""
        return float(self._state[0]["distance_m"])

    @property
    def swing_legs(self) -> tuple[str, ...]:
        """Legs in the air now."""
        return self._swing_legs

    @property
    def footholds(self) -> dict[str, np.ndarray]:
        """The planned touch-down point (3,) [m, world] of each leg in the air (copies)."""
        return {leg: self._footholds[LEGS.index(leg)].copy() for leg in self.swing_legs}

    def advance(self, now_s: float) -> WalkPhase:
        """Set the controller's references and contacts for time ``now_s`` [s]."""
        phase = self.phase
        if phase is None:
            raise ConfigurationError("Walking.advance: call start(now_s) first")
        dt = now_s - self._last_s
        if dt < 0.0:  # max(dt, 0.0) without the builtin's call
            dt = 0.0
        self._last_s = now_s
        if phase is _DONE:
            self._measure(dt)
            return phase
        if self._following:
            self._follow_command(dt)
        status = self._tick(now_s, dt, phase is _STOPPING)
        if status:
            self._handle_events(status)
        if self.phase is _STOPPING and self._settled():
            self._settle(now_s)
        return self.phase

    def _yaw(self) -> float:
        r = self.controller.kinematics.base_rotation
        return math.atan2(r[1, 0], r[0, 0])

    def _follow_command(self, dt: float) -> None:
        goal = self.envelope.scale(*self.target_velocity.tolist())
        now = self.commanded_velocity.tolist()
        if goal[0] == now[0] and goal[1] == now[1] and goal[2] == now[2]:
            self._following = False  # until the next command (or the stop)
            return
        accel = STOP_ACCEL if self.phase is WalkPhase.STOPPING else LINEAR_ACCEL
        ramped = [min(max(g - c, -limit), limit) for g, c, limit in
                  zip(goal, now, (accel * dt, accel * dt, YAW_ACCEL * dt), strict=True)]
        change = self.envelope.limit_change(*ramped, dt=dt, accel_mps2=max(HIP_ACCEL, accel))
        self.commanded_velocity[:] = [c + d for c, d in zip(now, change, strict=True)]

    def _set_leg(self, index: int, state: _Leg) -> None:
        self._legs[LEGS[index]] = state
        self._mode[index] = state.value
        # Read by viewers and recorders at their own rates: made at each change, not each read.
        self._swing_legs = tuple(leg for leg in LEGS if self._legs[leg] in _IN_THE_AIR)

    def _handle_events(self, status: int) -> None:
        """The state machine's part of the tick: the legs' events, in ``LEGS`` order."""
        ctrl, gait = self.controller, self.gait
        if status == TICK_COM_REFUSED:  # the setter raises, naming the value
            ctrl.set_com_target(self._com_ref, self._com_velocity)
        schedule = ctrl.schedule
        for index, event in enumerate(self._events.tolist()):
            leg = LEGS[index]
            if event == EV_UNLOAD and not schedule.is_ramping(leg):
                load = max(ctrl.normal_force(leg), schedule.min_normal_force_n)
                start = min(load, schedule.max_normal_force(leg))
                remaining = max(self.clock.time_to_liftoff(leg, self.gait_time_s),
                                ctrl.control_period_s)
                schedule.ramp_normal_force(leg, 0.0, remaining, from_n=start)
                self._lifted[index] = self._cycle[index]
                self._set_leg(index, _Leg.UNLOADING)
            elif event == EV_RELOAD:
                schedule.ramp_normal_force(leg, schedule.full_normal_force_n, gait.transfer_s)
                self._set_leg(index, _Leg.STANCE)
            elif event == EV_LIFT_OFF:
                schedule.set_swing(leg)
                foot = ctrl.foot_positions()[index]
                self._starts[index] = foot
                self._ground[index] = foot[2]
                self._set_leg(index, _Leg.SWING)
                if self.phase is WalkPhase.STARTING:
                    self.phase = WalkPhase.WALKING
                event = self._swing_leg(index)
            if event == EV_TOUCH_DOWN:
                self._touch_down(leg)
            elif event == EV_LATE:
                self._set_leg(index, _Leg.LATE)
            elif event == EV_REFUSED:  # the setter raises, naming the value
                ctrl.set_foot_target(leg, *self._path[index], clamp_to_reach=True)

    def _touch_down(self, leg: str) -> None:
        schedule = self.controller.schedule
        schedule.set_stance(leg, max_normal_force_n=0.0)
        schedule.ramp_normal_force(leg, schedule.full_normal_force_n, self.gait.transfer_s)
        self._set_leg(LEGS.index(leg), _Leg.STANCE)

    def _settled(self) -> bool:
        schedule = self.controller.schedule
        return (all(state is _Leg.STANCE for state in self._legs.values())
                and not any(schedule.is_ramping(leg) for leg in LEGS)
                and bool(self._state[0]["planted"]))

    def _settle(self, now_s: float) -> None:
        """On four loaded feet: the CoM to where it stood over them at the start, then DONE."""
        if self._settle_s is None:
            feet = self.controller.foot_positions()[:, :2]
            self._settle_to = (feet.mean(axis=0)
                               + yaw_rotation(self._yaw() - self._yaw0) @ self._home)
            # From the capture point: where the CoM would come to rest by itself.
            ctrl = self.controller
            self._settle_from = (ctrl.kinematics.com_position[:2] + self.planner.feedback_gain
                                 * ctrl.kinematics.com_velocity[:2])
            self._settle_s = now_s
        s = min_jerk((now_s - self._settle_s) / SETTLE_S)[0]
        self._com_ref[:2] = self._settle_from + s * (self._settle_to - self._settle_from)
        if now_s - self._settle_s >= SETTLE_S:
            self._finish()

    def _finish(self) -> None:
        ctrl = self.controller
        ctrl.schedule.min_stance = self._min_stance
        ctrl.com_task.set_weight(self._com_weight)
        ctrl.motor.retune(self._shaping)
        ctrl.set_com_target(self._com_ref)
        ctrl.base_task.reference[1, :] = 0.0
        self.commanded_velocity[:] = 0.0
        self.phase = WalkPhase.DONE


def _bound(kernel: Any, signature: Any, *groups: Any) -> Callable[..., Any]:
    """``kernel``'s overload for ``signature`` (compiled at import) with ``groups`` bound:
    the call skips the dispatcher's typing of every argument (about 40 ns an array)."""
    return functools.partial(kernel.overloads[signature.args].entry_point, *groups)
