"""Where a swinging foot lands: Raibert's rule with capture-point feedback, within reach."""

from __future__ import annotations

import math

import numba
import numpy as np

from wbc.core.validation import as_float

#: Gravity [m/s^2].
GRAVITY = 9.81


def yaw_rotation(yaw_rad: float) -> np.ndarray:
    """The (2, 2) rotation of the horizontal plane by ``yaw_rad`` [rad]."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s], [s, c]])


@numba.njit("UniTuple(f8, 2)(f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8)",
            cache=True)
def foothold_point(offset_x: float, offset_y: float, gain_s: float, max_step_m: float,
                   com_x: float, com_y: float, yaw_rad: float, cmd_x: float, cmd_y: float,
                   vel_x: float, vel_y: float, yaw_rate_cmd: float, time_to_touchdown_s: float,
                   stance_s: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """:meth:`FootholdPlanner.foothold_xy` for a leg's nominal offset (x, y) [m], the
    feedback gain [s] and the largest step [m]: the rule's one implementation, which the
    walking tick's compiled kernel calls too."""
    yaw = yaw_rad + yaw_rate_cmd * (time_to_touchdown_s + 0.5 * stance_s)
    c, s = math.cos(yaw), math.sin(yaw)
    hip_x = com_x + cmd_x * time_to_touchdown_s + (c * offset_x - s * offset_y)
    hip_y = com_y + cmd_y * time_to_touchdown_s + (s * offset_x + c * offset_y)
    k, half = gain_s, 0.5 * stance_s
    step_x = cmd_x * half + k * (vel_x - cmd_x) + 0.5 * k * (vel_y * yaw_rate_cmd)
    step_y = cmd_y * half + k * (vel_y - cmd_y) + 0.5 * k * (-vel_x * yaw_rate_cmd)
    length = math.hypot(step_x, step_y)
    if length > max_step_m:
        shrink = max_step_m / length
        step_x, step_y = step_x * shrink, step_y * shrink
    return hip_x + step_x, hip_y + step_y


class FootholdPlanner:
    """The touch-down point of a swinging foot (world frame, horizontal) from the commanded
    and the measured velocity.

    ``p = hip + v_cmd T_stance / 2 + sqrt(h / g) (v - v_cmd) + sqrt(h / g) / 2 (v x w_cmd)``:
    the hip is where the leg's nominal foot offset (from the centre of mass, in the heading
    frame) will be at touch-down, the heading turned by the yaw rate over the time to
    touch-down and half a stance; the foot then lands half a stance's travel ahead of it, so
    the hip passes over the foot at mid-stance (Raibert); a body faster than commanded puts
    its foot farther ahead by the capture point's offset (``sqrt(h / g)`` per m/s), which
    slows it within a step, and the last term leans the step into a turn. The offset from
    the hip is clamped to ``max_step_m`` (the leg's reach on the ground).
    """

    def __init__(self, offsets: dict[str, np.ndarray], *, com_height_m: float,
                 max_step_m: float, feedback_gain: float | None = None):
        """Args:
            offsets: Each leg's nominal foot position (2,) [m] relative to the centre of
                mass, in the heading frame (x forward, y left).
            com_height_m: Height [m] of the centre of mass above the ground.
            max_step_m: Largest horizontal distance [m] of a foothold from its hip.
            feedback_gain: Gain [s] on the velocity error; ``sqrt(h / g)`` (the capture
                point's) when ``None``.
        """
        self.offsets = {leg: np.array(o, dtype=float) for leg, o in offsets.items()}
        self._offsets_xy = {leg: (float(o[0]), float(o[1])) for leg, o in self.offsets.items()}
        self.com_height_m = as_float("com_height_m", com_height_m, low=0.05,
                                     low_inclusive=False)
        self.max_step_m = as_float("max_step_m", max_step_m, low=0.0, low_inclusive=False)
        self.feedback_gain = (math.sqrt(self.com_height_m / GRAVITY) if feedback_gain is None
                              else as_float("feedback_gain", feedback_gain, low=0.0))

    def hip(self, leg: str, com_xy: np.ndarray, yaw_rad: float) -> np.ndarray:
        """The leg's nominal foot position (2,) [m] for a CoM at ``com_xy`` and a heading."""
        return com_xy + yaw_rotation(yaw_rad) @ self.offsets[leg]

    def foothold(self, leg: str, *, com_xy: np.ndarray, yaw_rad: float,
                 velocity_cmd: np.ndarray, velocity: np.ndarray, yaw_rate_cmd: float,
                 time_to_touchdown_s: float, stance_s: float) -> np.ndarray:
        """The foothold (2,) [m, world frame] of ``leg``.

        Args:
            leg: The swinging leg.
            com_xy: The centre of mass now (2,) [m].
            yaw_rad: The heading now [rad].
            velocity_cmd: The commanded horizontal velocity (2,) [m/s], world frame.
            velocity: The measured horizontal velocity of the centre of mass (2,) [m/s].
            yaw_rate_cmd: The commanded yaw rate [rad/s].
            time_to_touchdown_s: Time [s] left in the swing.
            stance_s: The stance that follows [s].
        """
        return np.array(self.foothold_xy(
            leg, float(com_xy[0]), float(com_xy[1]), yaw_rad, float(velocity_cmd[0]),
            float(velocity_cmd[1]), float(velocity[0]), float(velocity[1]), float(yaw_rate_cmd),
            time_to_touchdown_s, stance_s))

    def foothold_xy(self, leg: str, com_x: float, com_y: float, yaw_rad: float,
                    cmd_x: float, cmd_y: float, vel_x: float, vel_y: float,
                    yaw_rate_cmd: float, time_to_touchdown_s: float,
                    stance_s: float) -> tuple[float, float]:
        """:meth:`foothold` on floats (x, y) [m] (:func:`foothold_point`, compiled)."""
        ox, oy = self._offsets_xy[leg]
        return foothold_point(ox, oy, self.feedback_gain, self.max_step_m, com_x, com_y,
                              yaw_rad, cmd_x, cmd_y, vel_x, vel_y, yaw_rate_cmd,
                              time_to_touchdown_s, stance_s)
