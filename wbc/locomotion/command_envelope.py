"""What a trot can follow: a velocity command scaled so that every stance foot stays within its
leg's reach, and changed at bounded accelerations of every hip."""

from __future__ import annotations

import math

from wbc.core.validation import as_float

#: Share of the foothold's largest step from the hip (``FootholdPlanner.max_step_m``, 0.19 m
#: on the GO2) that the command's half-stance travel may use: the hips at up to 1.05 m/s with
#: the default 0.275 s stance, so 1.0 m/s straight (0.1375 m) is not scaled. The rest, 0.048 m,
#: is for the capture-point feedback: 0.27 m/s of velocity error at its 0.18 s gain.
COMMAND_STEP_SHARE = 0.75
#: The share walking backward at ``BACKWARD_FULL_MPS`` or faster (blended linearly from
#: :data:`COMMAND_STEP_SHARE` at 0): the GO2's knees point backward, and backward 0.95 m/s
#: with 0.25 m/s sideways and 0.25 rad/s had 19 QP failures in 4 s at 0.75 (its forward
#: mirror none), none at 0.65; backward 1.0 m/s alone had 2.
BACKWARD_STEP_SHARE, BACKWARD_FULL_MPS = 0.65, 1.0
#: Largest acceleration [m/s^2] of any hip's commanded velocity: a reversal from 1 m/s
#: forward to 1 m/s backward with a turn moved the outer hips' velocity at up to 2.8 m/s^2 under
#: the per-axis ramps alone (2 m/s^2, 4 rad/s^2).
HIP_ACCEL = 2.0


class CommandEnvelope:
    """Scales a velocity command (forward, lateral [m/s], yaw rate [rad/s], heading frame) into
    what the gait can follow.

    A stance foot stays where it landed while its hip moves over it at the hip's velocity
    ``u = (vx - w y, vy + w x)`` (the hip at ``(x, y)`` from the centre of mass): the foothold
    rule puts it ``u T_stance / 2`` ahead of the hip, plus its lean into a turn,
    ``sqrt(h / g) / 2 (vy w, -vx w)``, so the foot ends about as far behind. The command is
    scaled down as a whole (its direction and curvature kept) until every leg's planned step
    fits :data:`COMMAND_STEP_SHARE` of the largest step; its changes are scaled down as a whole
    until no hip accelerates faster than :data:`HIP_ACCEL`.
    """

    def __init__(self, offsets: list[tuple[float, float]], *, stance_s: float,
                 max_step_m: float, turn_gain_s: float, step_share: float = COMMAND_STEP_SHARE,
                 backward_share: float = BACKWARD_STEP_SHARE, hip_accel_mps2: float = HIP_ACCEL):
        """Args:
            offsets: Each leg's nominal foot position (x, y) [m] from the centre of mass,
                heading frame.
            stance_s: A foot's stance time [s].
            max_step_m: The foothold's largest step from the hip [m].
            turn_gain_s: The foothold's gain [s] on ``v x w`` (half the capture point's).
            step_share: Share of ``max_step_m`` the command's steps may use.
            backward_share: The share walking backward at :data:`BACKWARD_FULL_MPS` or faster.
            hip_accel_mps2: Largest acceleration of a hip's commanded velocity [m/s^2].
        """
        self.offsets = [(float(x), float(y)) for x, y in offsets]
        self.half_stance_s = 0.5 * as_float("stance_s", stance_s, low=0.0, low_inclusive=False)
        self.turn_gain_s = as_float("turn_gain_s", turn_gain_s, low=0.0)
        step_share = as_float("step_share", step_share, low=0.0, high=1.0,
                              low_inclusive=False)
        backward_share = as_float("backward_share", backward_share, low=0.0, high=step_share,
                                  low_inclusive=False)
        #: The longest step [m] a command may plan from a hip (forward or sideways).
        self.max_step_m = step_share * as_float("max_step_m", max_step_m, low=0.0,
                                                low_inclusive=False)
        self._backward_loss_m = (step_share - backward_share) * max_step_m
        self.hip_accel_mps2 = as_float("hip_accel_mps2", hip_accel_mps2, low=0.0,
                                       low_inclusive=False)
        self._scaled: tuple[tuple[float, float, float], tuple[float, float, float]] = (
            (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

    def hip_speed(self, vx: float, vy: float, wz: float) -> float:
        """The fastest hip's speed [m/s] for a command."""
        return max(math.hypot(vx - wz * y, vy + wz * x) for x, y in self.offsets)

    def step(self, vx: float, vy: float, wz: float) -> float:
        """The longest step [m] from a hip the foothold rule plans for a command followed."""
        t, k = self.half_stance_s, self.turn_gain_s
        lean_x, lean_y = k * vy * wz, -k * vx * wz
        return max(math.hypot((vx - wz * y) * t + lean_x, (vy + wz * x) * t + lean_y)
                   for x, y in self.offsets)

    def longest_step(self, vx: float) -> float:
        """The longest step [m] allowed at a forward velocity ``vx`` [m/s]: shorter backward."""
        return self.max_step_m - self._backward_loss_m * min(max(-vx / BACKWARD_FULL_MPS, 0.0),
                                                             1.0)

    def scale(self, vx: float, vy: float, wz: float) -> tuple[float, float, float]:
        """The command scaled (as a whole) so that every step fits :meth:`longest_step`."""
        command = (vx, vy, wz)
        if command == self._scaled[0]:  # the same command as last time (every tick)
            return self._scaled[1]
        scaled = command
        if self.step(vx, vy, wz) > self.longest_step(vx):
            low, high = 0.0, 1.0  # bisection: the step grows with the scale (and its square)
            for _ in range(30):
                mid = 0.5 * (low + high)
                low, high = ((mid, high) if self.step(vx * mid, vy * mid, wz * mid)
                             <= self.longest_step(vx * mid) else (low, mid))
            scaled = (vx * low, vy * low, wz * low)
        self._scaled = (command, scaled)
        return scaled

    def limit_change(self, dvx: float, dvy: float, dwz: float, *, dt: float,
                     accel_mps2: float | None = None) -> tuple[float, float, float]:
        """A change of the command over ``dt`` [s] scaled (as a whole) so that no hip's
        velocity changes faster than ``accel_mps2`` [m/s^2] (:attr:`hip_accel_mps2` when
        ``None``; a stop passes its own deceleration)."""
        largest = (self.hip_accel_mps2 if accel_mps2 is None else accel_mps2) * dt
        fastest = self.hip_speed(dvx, dvy, dwz)
        if fastest <= largest:
            return dvx, dvy, dwz
        k = largest / fastest
        return dvx * k, dvy * k, dwz * k
