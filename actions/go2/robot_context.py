"""What the behaviours of one robot share: the controller, the latest state, its judgement."""

from __future__ import annotations

import math

import numpy as np

from actions.go2.velocity_stream import VelocityStream
from wbc.controller.balance_controller import BalanceController
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.model.description import LEGS
from wbc.model.support_polygon import SupportPolygon, capture_point_margin

#: Above this base tilt [deg] the robot is losing its balance.
TILT_LIMIT_DEG = 12.0
#: Below this capture-point margin [m] inside the support polygon the robot is losing it.
CAPTURE_MARGIN_LIMIT_M = 0.0
_GRAVITY = 9.81
#: The base is at least this high [m] when standing.
STANDING_HEIGHT_M = 0.25


def tilt_deg(q: np.ndarray) -> float:
    """Angle [deg] between the base's vertical axis and the world's, for a configuration
    ``q`` (Pinocchio convention: quaternion ``q[3:7]`` as x, y, z, w)."""
    x, y = q.item(3), q.item(4)  # Python floats without a NumPy scalar between
    return math.degrees(math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (x * x + y * y)))))


class RobotContext:
    """The controller plus the latest state it was given (estimated, on a GO2), updated by
    the control loop each tick."""

    def __init__(self, controller: BalanceController):
        self.controller = controller
        self.q = np.zeros(19)
        self.q[6] = 1.0
        self.v = np.zeros(18)
        self.now_s = 0.0
        self.last_output: ControlOutput | None = None
        #: Why the last tick was not OK ('' when it was).
        self.fault = ""
        #: Ticks in a row the controller could only send its damping fallback.
        self.consecutive_fallbacks = 0
        #: Why goals are refused now ('' when they are accepted): the loop has no
        #: trustworthy state, or is standing the robot up again after it had none.
        self.goal_refusal = ""
        #: One goal of this type is let through despite :attr:`goal_refusal` (the loop's own
        #: recovery stand); cleared when it is.
        self.admit_once: type | None = None
        #: What the robot is walking for ('' when it is not): goals other than a walk are
        #: refused while it walks (set and cleared by the Walk behaviour).
        self.walking = ""
        #: The streaming velocity command (``cmd_vel``) and the walks it starts.
        self.velocity_stream = VelocityStream()
        #: Rows of ``foot_positions()`` that make each support polygon seen so far.
        self._support_rows: dict[tuple[str, ...], np.ndarray] = {}
        self._weight_n = controller.description.total_mass * _GRAVITY  # [N]
        # The balance watch first runs when a foot unloads, mid-motion, where loading its
        # compiled code (its first call in a process) would stall that tick for
        # milliseconds: load it now, with arguments of the types the watch passes.
        capture_point_margin(controller.foot_positions(), np.arange(len(LEGS)), np.zeros(3),
                             np.zeros(3), 1.0, _GRAVITY)

    def record_output(self, out: ControlOutput) -> None:
        """Record the command sent this tick; any tick that is not OK is a controller fault."""
        self.last_output = out
        self.fault = "" if out.ok else out.message
        if out.status is ControlStatus.FALLBACK:
            self.consecutive_fallbacks += 1
        else:
            self.consecutive_fallbacks = 0

    def observe(self, now_s: float, q: np.ndarray, v: np.ndarray) -> None:
        """Record the state measured at ``now_s`` [s] (before the behaviours run)."""
        self.now_s, self.q, self.v = now_s, q, v

    def tilt_deg(self) -> float:
        """Angle [deg] between the base's vertical axis and the world's (:func:`tilt_deg`)."""
        return tilt_deg(self.q)

    def com_margin_m(self) -> float:
        """Centre of mass's distance [m] inside the support polygon of the loaded feet."""
        legs = self.controller.schedule.support_legs()
        if len(legs) < 3:
            return -math.inf
        feet = self.controller.foot_positions()
        points = np.array([feet[LEGS.index(leg), :2] for leg in legs])
        return SupportPolygon.signed_distance(points, self.controller.com_position())

    def capture_margin_m(self) -> float:
        """Capture point's distance [m] inside the polygon where the ZMP can be.

        The capture point ``c + c_dot / omega0`` (``omega0 = sqrt(g / z_com)``) is where the
        centre of mass would come to rest over. The ZMP can only be where every support foot
        carries at least the controller's minimum normal force: the support polygon shrunk
        about its centroid by ``1 - n f_min / (m g)``. With the capture point outside it, the
        robot cannot stop without changing its support (here: putting the raised foot down).
        """
        controller = self.controller
        legs = controller.schedule.support_legs()
        count = len(legs)
        if count < 3:
            return -math.inf
        key = tuple(legs)
        support = self._support_rows.get(key)
        if support is None:
            support = self._support_rows[key] = np.array([LEGS.index(leg) for leg in legs])
        weight = self._weight_n
        shrink = max(0.0, 1.0 - count * controller.schedule.min_normal_force_n / weight)
        return capture_point_margin(controller.foot_positions(), support,
                                    controller.com_position(), controller.com_velocity(),
                                    shrink, _GRAVITY)

    def is_upright(self) -> bool:
        """The base is level enough and high enough to stand."""
        return self.tilt_deg() < TILT_LIMIT_DEG and self.q[2] > 0.08

    def is_standing(self) -> bool:
        """Four feet in stance, base at standing height and level."""
        return (len(self.controller.schedule.stance_legs) == len(LEGS)
                and self.q[2] > STANDING_HEIGHT_M
                and self.tilt_deg() < 5.0)

    def balance_problem(self) -> str:
        """Why the balance is being lost ('' when it is not)."""
        tilt = self.tilt_deg()
        if tilt > TILT_LIMIT_DEG:
            return f"base tilt {tilt:.1f} deg above {TILT_LIMIT_DEG:.0f} deg"
        margin = self.capture_margin_m()
        if margin < CAPTURE_MARGIN_LIMIT_M:
            return (f"capture point {-margin * 1e3:.1f} mm outside the polygon the feet can "
                    f"hold the ZMP in; centre of mass {self.com_margin_m() * 1e3:.1f} mm inside "
                    "the support polygon")
        return ""
