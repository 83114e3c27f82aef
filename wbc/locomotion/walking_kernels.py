"""The walking tick's continuous part, compiled: measure, body references, swing paths.

:class:`wbc.locomotion.Walking` keeps the gait's state machine (unload, lift-off,
touch-down, late, the stop) in Python, a few events a step; everything it computed every
tick is one call of :func:`walking_tick`: the measured velocity and the path walked, the
gait clock, the CoM and base references, the stepping's end after a stop, each leg's phase,
each swinging foot's foothold, path, reach clamp and landing test, a late foot's descent.
It writes the task references where the tasks keep them, after the checks their setters
make (3 finite numbers each); a value refused is left unwritten and reported, and the
caller then calls the setter, which raises naming it. The arithmetic is the Python code's
before it, operation for operation, so the references are the same to the last bit but
where ``math.hypot`` rounds differently (CPython's own against the C library's: an ulp, seen
in the walk gait's CoM lead, 8e-11 m on the feet after 4 s of closed loop; docs/walking.md).
"""

from __future__ import annotations

import math

import numba
from numba import types
from numba.extending import intrinsic

from wbc.controller.foot_reach import LEG_REACH_M
from wbc.locomotion.foothold_planner import foothold_point
from wbc.locomotion.swing_trajectory import swing_path
from wbc.locomotion.walking_groups import (
    ADDRESS_DTYPE,
    EV_LATE,
    EV_LIFT_OFF,
    EV_NONE,
    EV_REFUSED,
    EV_RELOAD,
    EV_TOUCH_DOWN,
    EV_UNLOAD,
    LATE,
    PARAMS_DTYPE,
    STANCE,
    STATE_DTYPE,
    SWING,
    TICK_COM_REFUSED,
    TICK_EVENTS,
    TICK_QUIET,
    UNLOADING,
    Measured,
    Targets,
)
from wbc.locomotion.walking_tuning import (
    COM_LEAD_M,
    HEIGHT_KI,
    HEIGHT_TRIM_M,
    LATE_MAX_S,
    LATE_SPEED_MPS,
    NEAR_M,
    STOP_SPEED_MPS,
    STOP_STEPPING_S,
    STOP_YAW_RATE,
    STOPPED_MPS,
    TOUCH_M,
)

# Explicit signatures, so that numba compiles (or reads from its cache) at import, not in
# the control tick that starts a walk.
ADDRESS_TYPE = types.Array(numba.from_dtype(ADDRESS_DTYPE), 1, "C")
PARAMS_TYPE = types.Array(numba.from_dtype(PARAMS_DTYPE), 1, "C")
STATE_TYPE = types.Array(numba.from_dtype(STATE_DTYPE), 1, "C")
TICK_SIGNATURE = types.int64(ADDRESS_TYPE, PARAMS_TYPE, STATE_TYPE, types.float64,
                             types.float64, types.boolean)
SWING_SIGNATURE = types.int64(ADDRESS_TYPE, PARAMS_TYPE, STATE_TYPE, types.int64)
MEASURE_SIGNATURE = types.void(ADDRESS_TYPE, STATE_TYPE, types.float64)


@intrinsic
def _float64_pointer(typingctx, address):  # pragma: no cover - compiled
    """The float64 data at ``address`` (an int64, from :func:`address_record`)."""
    signature = types.CPointer(types.float64)(types.int64)

    def codegen(context, builder, sig, args):
        return builder.inttoptr(args[0], context.get_value_type(sig.return_type))

    return signature, codegen


@numba.njit(cache=True)
def _measured(a):  # pragma: no cover - compiled
    """The kinematics' arrays at the record's addresses."""
    return Measured(numba.carray(_float64_pointer(a.com_position), (3,)),
                    numba.carray(_float64_pointer(a.com_velocity), (3,)),
                    numba.carray(_float64_pointer(a.base_rotation), (3, 3)),
                    numba.carray(_float64_pointer(a.base_position), (3,)),
                    numba.carray(_float64_pointer(a.base_velocity), (6,)),
                    numba.carray(_float64_pointer(a.feet_position), (4, 3)))


@numba.njit(cache=True)
def _targets(a):  # pragma: no cover - compiled
    """The task references at the record's addresses."""
    feet = a.foot_references
    return Targets(numba.carray(_float64_pointer(a.com_reference), (3, 3)),
                   numba.carray(_float64_pointer(a.base_rotation_target), (3, 3)),
                   numba.carray(_float64_pointer(a.base_reference), (3, 3)),
                   (numba.carray(_float64_pointer(feet[0]), (3, 3)),
                    numba.carray(_float64_pointer(feet[1]), (3, 3)),
                    numba.carray(_float64_pointer(feet[2]), (3, 3)),
                    numba.carray(_float64_pointer(feet[3]), (3, 3))))


@numba.njit(cache=True)
def _finite3(values, row):  # pragma: no cover - compiled
    """Whether row ``row`` of ``values`` holds 3 finite numbers."""
    return (math.isfinite(values[row, 0]) and math.isfinite(values[row, 1])
            and math.isfinite(values[row, 2]))


@numba.njit(cache=True)
def _measure(measured, s, dt):  # pragma: no cover - compiled
    """The measured velocity (heading frame) and the path walked, from the kinematics."""
    vx, vy = measured.com_velocity[0], measured.com_velocity[1]
    rotation, w = measured.base_rotation, measured.v
    c, si = rotation[0, 0], rotation[1, 0]
    s.yaw_now = math.atan2(si, c)
    norm = math.hypot(c, si)
    if norm == 0.0:
        norm = 1.0
    c, si = c / norm, si / norm
    omega = rotation[2, 0] * w[3] + rotation[2, 1] * w[4] + rotation[2, 2] * w[5]
    s.measured_velocity[0] = c * vx + si * vy
    s.measured_velocity[1] = -si * vx + c * vy
    s.measured_velocity[2] = omega
    s.distance_m += math.hypot(vx, vy) * dt


@numba.njit(cache=True)
def _track_body(measured, targets, p, s, dt):  # pragma: no cover - compiled
    """The CoM reference moved with the command (dragged at most COM_LEAD_M ahead of the
    CoM), its height above the stance feet trimmed by the base height's error; the heading
    turned by the yaw rate. False (nothing written to the task) for a non-finite target."""
    c, si = math.cos(s.yaw_ref), math.sin(s.yaw_ref)
    cmd = s.commanded_velocity
    vx, vy, yaw_rate = cmd[0], cmd[1], cmd[2]
    wx, wy = c * vx - si * vy, si * vx + c * vy
    s.com_velocity[0], s.com_velocity[1] = wx, wy
    ref = s.com_ref
    x, y = ref[0] + wx * dt, ref[1] + wy * dt
    lead_x, lead_y = x - measured.com_position[0], y - measured.com_position[1]
    distance = math.hypot(lead_x, lead_y)
    if distance > COM_LEAD_M:
        pull = 1.0 - COM_LEAD_M / distance
        x, y = x - lead_x * pull, y - lead_y * pull
    # The ground: the stance feet's (their spheres' centres) mean height, else all four's.
    standing, count, every = 0.0, 0, 0.0
    for i in range(4):
        z = measured.frame_position[i, 2]
        every += z
        if s.mode[i] == STANCE:
            standing += z
            count += 1
    ground = standing / count if count else every / 4.0
    height = measured.base_position[2] - ground
    s.trim = min(max(s.trim + HEIGHT_KI * (p.base_height_m - height) * dt, -HEIGHT_TRIM_M),
                 HEIGHT_TRIM_M)
    ref[0], ref[1], ref[2] = x, y, ground + p.com_height_m + s.trim
    velocity = s.com_velocity
    for k in range(3):  # ComTask.set_motion's check: finite target and velocity
        if not (math.isfinite(ref[k]) and math.isfinite(velocity[k])):
            return False
    com = targets.com
    for k in range(3):
        com[0, k], com[1, k], com[2, k] = ref[k], velocity[k], 0.0
    s.yaw_ref += yaw_rate * dt
    c, si = math.cos(s.yaw_ref), math.sin(s.yaw_ref)
    # The command in the world at the new heading: what the footholds plan with.
    s.cmd_world[0], s.cmd_world[1] = c * vx - si * vy, si * vx + c * vy
    rotation, reference = targets.base_rotation, targets.base_reference
    rotation[0, 0], rotation[0, 1], rotation[1, 0], rotation[1, 1] = c, -si, si, c
    reference[1, 0], reference[1, 1], reference[1, 2] = 0.0, 0.0, yaw_rate
    return True


@numba.njit(cache=True)
def _set_foot(measured, targets, p, path, i):  # pragma: no cover - compiled
    """WholeBodyController.set_foot_target(clamp_to_reach=True) of ``path`` (3, 3) for leg
    ``i``: a position beyond LEG_REACH_M from the shoulder moved onto it; False (nothing
    written) when a value is not finite."""
    rotation, base = measured.base_rotation, measured.base_position
    s0, s1, s2 = p.shoulder[i, 0], p.shoulder[i, 1], p.shoulder[i, 2]
    total = 0.0
    for r in range(3):  # FootReach's distance check, in its order
        shoulder = base[r] + rotation[r, 0] * s0 + rotation[r, 1] * s1 + rotation[r, 2] * s2
        offset = path[0, r] - shoulder
        total += offset * offset
    if not (_finite3(path, 0) and _finite3(path, 1) and _finite3(path, 2)):
        return False
    out = targets.feet[i]
    for r in range(3):
        out[0, r] = path[0, r]
    if math.sqrt(total) > LEG_REACH_M:
        # FootReach's clamp: the shoulder and the distance again (as its NumPy code computes
        # them), the target moved onto the reach towards the shoulder.
        x = rotation[0, 0] * s0 + rotation[0, 1] * s1 + rotation[0, 2] * s2 + base[0]
        y = rotation[1, 0] * s0 + rotation[1, 1] * s1 + rotation[1, 2] * s2 + base[1]
        z = rotation[2, 0] * s0 + rotation[2, 1] * s1 + rotation[2, 2] * s2 + base[2]
        ox, oy, oz = path[0, 0] - x, path[0, 1] - y, path[0, 2] - z
        distance = math.sqrt(ox * ox + oy * oy + oz * oz)
        if distance > LEG_REACH_M:
            scale = LEG_REACH_M / distance
            out[0, 0], out[0, 1], out[0, 2] = x + ox * scale, y + oy * scale, z + oz * scale
    for r in range(3):
        out[1, r], out[2, r] = path[1, r], path[2, r]
    return True


@numba.njit(cache=True)
def _landed(measured, p, s, i):  # pragma: no cover - compiled
    """The foot is down: on the ground it left from, or near it and stopped."""
    z = measured.frame_position[i, 2]
    previous = s.foot_z[i] if s.foot_seen[i] else z
    s.foot_z[i], s.foot_seen[i] = z, 1
    above = z - s.ground[i]
    stopped = abs(z - previous) < STOPPED_MPS * p.control_period_s
    return above <= TOUCH_M or (above <= NEAR_M and stopped)


@numba.njit(cache=True)
def _swing(measured, targets, p, s, i, cycle, phase):  # pragma: no cover - compiled
    """A swinging foot: its foothold (re-planned until 85 % of the swing), its path, its
    target; the event: landed, late, refused or none."""
    done = cycle != s.lifted[i]  # the clock passed the touch-down
    progress = 1.0 if done else (phase - p.duty_factor) / (1.0 - p.duty_factor)
    hold = s.footholds[i]
    if progress < 0.85:  # the foothold is fixed for the last part of the swing
        left = (1.0 - progress) * p.swing_s
        cmd = s.commanded_velocity
        hold[0], hold[1] = foothold_point(
            p.nominal[i, 0], p.nominal[i, 1], p.feedback_gain, p.max_step_m,
            measured.com_position[0], measured.com_position[1], s.yaw_now, s.cmd_world[0],
            s.cmd_world[1], measured.com_velocity[0], measured.com_velocity[1], cmd[2], left,
            p.stance_s)
        hold[2] = s.ground[i] - p.touchdown_press_m
    start, path = s.starts[i], s.path[i]
    swing_path(path, start[0], start[1], start[2], hold[0], hold[1], hold[2],
               p.swing_height_m, progress, p.swing_s)
    if not _set_foot(measured, targets, p, path, i):
        return EV_REFUSED
    if progress >= 0.5 and _landed(measured, p, s, i):
        return EV_TOUCH_DOWN  # early, or on time
    if done:
        for k in range(3):
            s.late_target[i, k] = path[0, k]
        s.late_s[i] = 0.0
        return EV_LATE
    return EV_NONE


@numba.njit(cache=True)
def _phase(p, s, i):  # pragma: no cover - compiled
    """Leg ``i``'s cycle number and phase in it (GaitClock.cycle)."""
    position = s.gait_time_s / p.period_s - p.offsets[i]
    cycle = math.floor(position)
    return cycle, position - cycle


@numba.njit(cache=True)
def _stepping(s, now_s, stopping):  # pragma: no cover - compiled
    """Whether new steps start: always, until a stop has slowed the robot (or has stepped
    for STOP_STEPPING_S); from then on, never."""
    if s.planted:
        return False
    if not stopping:
        return True
    cmd, measured = s.commanded_velocity, s.measured_velocity
    slow = (cmd[0] == 0.0 and cmd[1] == 0.0 and cmd[2] == 0.0
            and math.hypot(measured[0], measured[1]) < STOP_SPEED_MPS
            and abs(measured[2]) < STOP_YAW_RATE)
    planted = slow or now_s - s.stop_s > STOP_STEPPING_S
    s.planted = 1 if planted else 0
    return not planted


@numba.njit(TICK_SIGNATURE, cache=True)
def walking_tick(addresses, params, state, now_s, dt, stopping):  # pragma: no cover - compiled
    """One control tick of a walk at ``now_s`` [s], ``dt`` [s] after the last one
    (``stopping``: a stop was requested). Fills ``state.events`` (``EV_*`` per leg).

    Returns:
        ``TICK_QUIET`` (no event), ``TICK_EVENTS``, or ``TICK_COM_REFUSED`` (the CoM target
        not finite: nothing after it was done).
    """
    p, s = params[0], state[0]
    measured, targets = _measured(addresses[0]), _targets(addresses[0])
    _measure(measured, s, dt)
    late = False
    for i in range(4):
        s.events[i] = EV_NONE
        late = late or s.mode[i] == LATE
    if not late:  # a late foot holds the clock, so the other pair does not lift before it lands
        s.gait_time_s += dt
    if not _track_body(measured, targets, p, s, dt):
        return TICK_COM_REFUSED
    stepping = _stepping(s, now_s, stopping)
    status = TICK_QUIET
    for i in range(4):
        cycle, phase = _phase(p, s, i)
        s.cycle[i] = cycle
        mode, event = s.mode[i], EV_NONE
        if mode == STANCE:
            if stepping and p.window <= phase < p.duty_factor and s.lifted[i] != cycle:
                event = EV_UNLOAD
        elif mode == UNLOADING:
            if not stepping:  # a stop: load the foot again rather than lift it
                event = EV_RELOAD
            elif phase >= p.duty_factor or cycle != s.lifted[i]:
                event = EV_LIFT_OFF
        elif mode == SWING:
            event = _swing(measured, targets, p, s, i, cycle, phase)
        else:  # LATE: keep going down until the foot meets the ground
            target, path = s.late_target[i], s.path[i]
            target[2] -= LATE_SPEED_MPS * dt
            for k in range(3):
                path[0, k], path[1, k], path[2, k] = target[k], 0.0, 0.0
            path[1, 2] = -LATE_SPEED_MPS
            if not _set_foot(measured, targets, p, path, i):
                event = EV_REFUSED
            else:
                s.late_s[i] += dt
                if _landed(measured, p, s, i) or s.late_s[i] >= LATE_MAX_S:
                    event = EV_TOUCH_DOWN
        if event != EV_NONE:
            s.events[i] = event
            status = TICK_EVENTS
            if event == EV_REFUSED:
                return status  # as the setter would raise: the legs after it untouched
    return status


@numba.njit(SWING_SIGNATURE, cache=True)
def walking_swing(addresses, params, state, leg):  # pragma: no cover - compiled
    """Leg ``leg``'s swing at this tick (the tick it lifted off): its event (``EV_*``)."""
    p, s = params[0], state[0]
    measured, targets = _measured(addresses[0]), _targets(addresses[0])
    cycle, phase = _phase(p, s, leg)
    return _swing(measured, targets, p, s, leg, cycle, phase)


@numba.njit(MEASURE_SIGNATURE, cache=True)
def walking_measure(addresses, state, dt):  # pragma: no cover - compiled
    """The measured velocity and the path walked only (a walk that is done)."""
    _measure(_measured(addresses[0]), state[0], dt)
