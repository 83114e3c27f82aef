"""Walking on velocity commands: a periodic gait on the whole-body controller's contact
schedule, swing feet on smooth paths to footholds from the commanded and measured velocity."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from wbc.controller.balance_controller import BalanceController
from wbc.controller.foot_reach import LEG_REACH_M
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.core.min_jerk import min_jerk
from wbc.locomotion.command_envelope import HIP_ACCEL, CommandEnvelope
from wbc.locomotion.foothold_planner import FootholdPlanner, yaw_rotation
from wbc.locomotion.gait import GaitClock, GaitParameters, VelocityLimits
from wbc.locomotion.swing_trajectory import swing_reference
from wbc.locomotion.walk_phase import LegState as _Leg
from wbc.locomotion.walk_phase import WalkPhase
from wbc.locomotion.walking_tuning import (
    COM_LEAD_M,
    COM_WEIGHT,
    HEIGHT_KI,
    HEIGHT_TRIM_M,
    LATE_MAX_S,
    LATE_SPEED_MPS,
    LINEAR_ACCEL,
    NEAR_M,
    SETTLE_S,
    STOP_ACCEL,
    STOP_SPEED_MPS,
    STOP_STEPPING_S,
    STOP_YAW_RATE,
    STOPPED_MPS,
    SWING_KD,
    TOUCH_M,
    VELOCITY_LEAD_RAD_S,
    YAW_ACCEL,
)
from wbc.model.description import LEGS


class Walking:
    """Drives a :class:`WholeBodyController` through a gait on velocity commands.

    A motion like :class:`wbc.LegLift`: :meth:`start` once, :meth:`set_velocity` any time,
    :meth:`advance` every control tick before ``controller.step``; :meth:`request_stop` ends
    on four loaded feet. The feet are unloaded before a lift-off and reloaded after a
    touch-down by the contact schedule's force ramps (``transfer_s`` each). Positions are
    world-frame [m]; velocities in the heading frame (x forward, y left).
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
        #: Commanded velocity: forward, lateral [m/s], yaw rate [rad/s] (heading frame),
        #: as it follows the last command at bounded accelerations.
        self.commanded_velocity = np.zeros(3)
        self.target_velocity = np.zeros(3)
        self.measured_velocity = np.zeros(3)
        self.distance_m = 0.0
        self.footholds: dict[str, np.ndarray] = {}
        self.gait_time_s = 0.0
        self._legs = dict.fromkeys(LEGS, _Leg.STANCE)
        self._path = np.zeros((3, 3))
        self._path_rows = (self._path[0], self._path[1], self._path[2])  # views, set in place
        self._lowering = np.array([0.0, 0.0, -LATE_SPEED_MPS])  # a late foot's velocity [m/s]
        self._index = {leg: i for i, leg in enumerate(LEGS)}
        self._offsets = dict(zip(LEGS, self.gait.offsets, strict=True))
        #: The share of the cycle at which a stance leg's unloading may start.
        self._window = self.gait.duty_factor - self.gait.transfer_s / self.gait.period_s
        self._com_velocity = np.zeros(3)  # the CoM target's velocity [m/s], set every tick
        self._starts: dict[str, np.ndarray] = {}       # each swing's lift-off point [m]
        self._late_target: dict[str, np.ndarray] = {}  # a late foot's target [m]
        self._late_s: dict[str, float] = {}            # how long it has been late [s]
        self._foot_z: dict[str, float] = {}            # each foot's height last tick [m]

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
        self._com_ref = com.copy()
        # Where the CoM stands over the feet (from their centroid, heading frame at _yaw0).
        self._home, self._yaw0 = com[:2] - feet[:, :2].mean(axis=0), yaw
        self._settle_s: float | None = None
        self._planted = False  # a stop has ended the stepping
        self._com_height = float(com[2]) - ground  # above the ground
        #: The base height [m] above the ground that walking holds: the height at the start.
        self.base_height_m = float(ctrl.kinematics.base_position[2]) - ground
        self._trim = 0.0
        self._yaw_ref = yaw
        self._ground = {leg: float(feet[i, 2]) for i, leg in enumerate(LEGS)}
        self._lifted = dict.fromkeys(LEGS, -10)
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
        self.gait_time_s = ((first + gait.duty_factor) * gait.period_s - gait.transfer_s
                            - 2 * ctrl.control_period_s)
        self._last_s = now_s
        self._stop_s: float | None = None
        self.phase = WalkPhase.STARTING

    def request_stop(self, now_s: float) -> None:
        """Zero velocity: the walk takes its last steps and ends on four loaded feet."""
        if self.phase in (None, WalkPhase.DONE, WalkPhase.STOPPING):
            return
        self.target_velocity[:] = 0.0
        self._stop_s = now_s
        self.phase = WalkPhase.STOPPING

    @property
    def gait_phase(self) -> float:
        """Position in the gait cycle, ``[0, 1)``."""
        return (self.gait_time_s / self.gait.period_s) % 1.0

    @property
    def swing_legs(self) -> tuple[str, ...]:
        """Legs in the air now."""
        return tuple(leg for leg in LEGS if self._legs[leg] in (_Leg.SWING, _Leg.LATE))

    def advance(self, now_s: float) -> WalkPhase:
        """Set the controller's references and contacts for time ``now_s`` [s]."""
        if self.phase is None:
            raise ConfigurationError("Walking.advance: call start(now_s) first")
        dt = max(now_s - self._last_s, 0.0)
        self._last_s = now_s
        self._measure(dt)
        if self.phase is WalkPhase.DONE:
            return self.phase
        self._follow_command(dt)
        if _Leg.LATE not in self._legs.values():
            self.gait_time_s += dt
        self._track_body(dt)
        stepping = self._stepping(now_s)
        for leg in LEGS:
            self._advance_leg(leg, dt, stepping)
        if self.phase is WalkPhase.STOPPING and self._settled():
            self._settle(now_s)
        return self.phase

    def _yaw(self) -> float:
        r = self.controller.kinematics.base_rotation
        return math.atan2(r[1, 0], r[0, 0])

    def _measure(self, dt: float) -> None:
        # Python floats in the tick's helpers: NumPy on 2- and 3-vectors costs more than the math.
        kin = self.controller.kinematics
        vx, vy, _ = self._com_v = kin.com_velocity.tolist()
        (c, _, _), (s, _, _), (r20, r21, r22) = kin.base_rotation.tolist()
        self._yaw_now = math.atan2(s, c)
        norm = math.hypot(c, s) or 1.0
        c, s = c / norm, s / norm
        w3, w4, w5 = kin.v[3:6].tolist()
        omega = r20 * w3 + r21 * w4 + r22 * w5
        self.measured_velocity[:] = (c * vx + s * vy, -s * vx + c * vy, omega)
        self.distance_m += math.hypot(vx, vy) * dt

    def _follow_command(self, dt: float) -> None:
        goal = self.envelope.scale(*self.target_velocity.tolist())
        now = self.commanded_velocity.tolist()
        if goal[0] == now[0] and goal[1] == now[1] and goal[2] == now[2]:
            return  # following it already (most ticks)
        accel = STOP_ACCEL if self.phase is WalkPhase.STOPPING else LINEAR_ACCEL
        ramped = [min(max(g - c, -limit), limit) for g, c, limit in
                  zip(goal, now, (accel * dt, accel * dt, YAW_ACCEL * dt), strict=True)]
        change = self.envelope.limit_change(*ramped, dt=dt, accel_mps2=max(HIP_ACCEL, accel))
        self.commanded_velocity[:] = [c + d for c, d in zip(now, change, strict=True)]

    def _track_body(self, dt: float) -> None:
        """The CoM reference moves with the command, the heading turns with the yaw rate."""
        ctrl = self.controller
        kin = ctrl.kinematics
        c, s = math.cos(self._yaw_ref), math.sin(self._yaw_ref)
        vx, vy, yaw_rate = self._cmd = self.commanded_velocity.tolist()
        velocity = self._com_velocity
        wx, wy = c * vx - s * vy, s * vx + c * vy
        velocity[0], velocity[1] = wx, wy
        ref = self._com_ref
        rx, ry, _ = ref.tolist()
        x, y = rx + wx * dt, ry + wy * dt
        cx, cy, _ = self._com_p = kin.com_position.tolist()
        lead_x, lead_y = x - cx, y - cy
        distance = math.hypot(lead_x, lead_y)
        if distance > COM_LEAD_M:
            pull = 1.0 - COM_LEAD_M / distance
            x, y = x - lead_x * pull, y - lead_y * pull
        ground = self._ground_now()
        height = kin.base_position[2].item() - ground
        self._trim = min(max(self._trim + HEIGHT_KI * (self.base_height_m - height) * dt,
                             -HEIGHT_TRIM_M), HEIGHT_TRIM_M)
        # Above the stance feet: the estimate's height drifts, the legs' length does not.
        ref[:] = (x, y, ground + self._com_height + self._trim)
        ctrl.set_com_target(ref, velocity)
        self._yaw_ref += yaw_rate * dt
        c, s = math.cos(self._yaw_ref), math.sin(self._yaw_ref)
        # The command in the world at the new heading: what the footholds plan with.
        self._cmd_world = (c * vx - s * vy, s * vx + c * vy)
        task = ctrl.base_task
        rotation = task.rotation
        rotation[0, 0], rotation[0, 1], rotation[1, 0], rotation[1, 1] = c, -s, s, c
        reference = task.reference
        reference[1, 0], reference[1, 1], reference[1, 2] = 0.0, 0.0, yaw_rate

    def _ground_now(self) -> float:
        """The ground's height [m]: the stance feet's (their spheres' centres) mean."""
        heights = self.controller.kinematics.frame_position[:4, 2].tolist()
        standing = [z for z, leg in zip(heights, LEGS) if self._legs[leg] is _Leg.STANCE]
        return sum(standing) / len(standing) if standing else sum(heights) / 4.0

    def _stepping(self, now_s: float) -> bool:
        """Whether new steps start: always, until a stop has slowed the robot (or has
        stepped for STOP_STEPPING_S); from then on, never."""
        if self._planted:
            return False
        if self.phase is not WalkPhase.STOPPING or self._stop_s is None:
            return True
        slow = (not self.commanded_velocity.any()
                and math.hypot(*self.measured_velocity[:2]) < STOP_SPEED_MPS
                and abs(self.measured_velocity[2]) < STOP_YAW_RATE)
        self._planted = slow or now_s - self._stop_s > STOP_STEPPING_S
        return not self._planted

    def _advance_leg(self, leg: str, dt: float, stepping: bool) -> None:
        ctrl, gait = self.controller, self.gait
        schedule = ctrl.schedule
        state = self._legs[leg]
        # GaitClock.cycle, inline (every leg, every tick).
        position = self.gait_time_s / gait.period_s - self._offsets[leg]
        cycle = math.floor(position)
        phase = position - cycle
        if state is _Leg.STANCE:
            if (stepping and self._window <= phase < gait.duty_factor
                    and self._lifted[leg] != cycle and not schedule.is_ramping(leg)):
                load = max(ctrl.normal_force(leg), schedule.min_normal_force_n)
                start = min(load, schedule.max_normal_force(leg))
                remaining = max(self.clock.time_to_liftoff(leg, self.gait_time_s),
                                ctrl.control_period_s)
                schedule.ramp_normal_force(leg, 0.0, remaining, from_n=start)
                self._lifted[leg] = cycle
                self._legs[leg] = _Leg.UNLOADING
        elif state is _Leg.UNLOADING:
            if not stepping:  # a stop: load the foot again rather than lift it
                schedule.ramp_normal_force(leg, schedule.full_normal_force_n, gait.transfer_s)
                self._legs[leg] = _Leg.STANCE
            elif phase >= gait.duty_factor or cycle != self._lifted[leg]:
                schedule.set_swing(leg)
                foot = ctrl.foot_positions()[LEGS.index(leg)]
                self._starts[leg] = foot.copy()
                self._ground[leg] = float(foot[2])
                self._legs[leg] = _Leg.SWING
                if self.phase is WalkPhase.STARTING:
                    self.phase = WalkPhase.WALKING
                self._swing(leg, cycle, phase)
        elif state is _Leg.SWING:
            self._swing(leg, cycle, phase)
        else:  # LATE: keep going down until the foot meets the ground
            target = self._late_target[leg]
            target[2] -= LATE_SPEED_MPS * dt
            ctrl.set_foot_target(leg, target, self._lowering, clamp_to_reach=True)
            self._late_s[leg] += dt
            if self._landed(leg) or self._late_s[leg] >= LATE_MAX_S:
                self._touch_down(leg)

    def _swing(self, leg: str, cycle: int, phase: float) -> None:
        ctrl, gait = self.controller, self.gait
        done = cycle != self._lifted[leg]  # the clock passed the touch-down
        progress = 1.0 if done else (phase - gait.duty_factor) / (1.0 - gait.duty_factor)
        if progress < 0.85:  # the foothold is fixed for the last part of the swing
            left = (1.0 - progress) * gait.swing_s
            (cx, cy, _), (vx, vy, _) = self._com_p, self._com_v
            x, y = self.planner.foothold_xy(leg, cx, cy, self._yaw_now, *self._cmd_world, vx, vy,
                                            self._cmd[2], left, gait.stance_s)
            self.footholds[leg] = np.array((x, y, self._ground[leg] - gait.touchdown_press_m))
        path = swing_reference(self._path, self._starts[leg], self.footholds[leg],
                               height_m=gait.swing_height_m, progress=progress,
                               duration_s=gait.swing_s)
        ctrl.set_foot_target(leg, *self._path_rows, clamp_to_reach=True)
        if progress >= 0.5 and self._landed(leg):
            self._touch_down(leg)  # early, or on time
        elif done:
            self._late_target[leg] = path[0].copy()
            self._late_s[leg] = 0.0
            self._legs[leg] = _Leg.LATE

    def _landed(self, leg: str) -> bool:
        """The foot is down: on the ground it left from, or near it and stopped."""
        z = self.controller.kinematics.frame_position[self._index[leg], 2].item()
        previous, self._foot_z[leg] = self._foot_z.get(leg, z), z
        above = z - self._ground[leg]
        stopped = abs(z - previous) < STOPPED_MPS * self.controller.control_period_s
        return above <= TOUCH_M or (above <= NEAR_M and stopped)

    def _touch_down(self, leg: str) -> None:
        schedule = self.controller.schedule
        schedule.set_stance(leg, max_normal_force_n=0.0)
        schedule.ramp_normal_force(leg, schedule.full_normal_force_n, self.gait.transfer_s)
        self._legs[leg] = _Leg.STANCE
        self.footholds.pop(leg, None)

    def _settled(self) -> bool:
        schedule = self.controller.schedule
        return (all(state is _Leg.STANCE for state in self._legs.values())
                and not any(schedule.is_ramping(leg) for leg in LEGS)
                and self._planted)

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
