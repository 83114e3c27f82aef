"""Where a swinging foot lands: Raibert's rule with capture-point feedback, within reach."""

from __future__ import annotations

import math

import numpy as np

from wbc.core.validation import as_float

#: Gravity [m/s^2].
GRAVITY = 9.81


def yaw_rotation(yaw_rad: float) -> np.ndarray:
    """The (2, 2) rotation of the horizontal plane by ``yaw_rad`` [rad]."""
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([[c, -s], [s, c]])


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
        com_td = com_xy + velocity_cmd * time_to_touchdown_s
        hip = self.hip(leg, com_td, yaw_rad + yaw_rate_cmd * (time_to_touchdown_s
                                                             + 0.5 * stance_s))
        k = self.feedback_gain
        cross = np.array([velocity[1] * yaw_rate_cmd, -velocity[0] * yaw_rate_cmd])
        step = velocity_cmd * (0.5 * stance_s) + k * (velocity - velocity_cmd) + 0.5 * k * cross
        length = math.hypot(step[0], step[1])
        if length > self.max_step_m:
            step *= self.max_step_m / length
        return hip + step
