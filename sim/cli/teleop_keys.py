"""The keyboard teleop's keys (``go2-wbc teleop``): bytes read from a terminal in raw mode
to a velocity command, one step a key press, held until changed (as ROS's
teleop_twist_keyboard does), within the walking limits.

======================= =====================================================================
key                     does
======================= =====================================================================
``w`` or up arrow       forward velocity one step up (0.1 m/s)
``s`` or down arrow     one step down (backwards past zero)
``a`` / ``d``           leftward velocity one step up / down (0.1 m/s)
``q`` or left arrow     turning rate one step counter-clockwise (0.2 rad/s)
``e`` or right arrow    one step clockwise
space or ``x``          stop: every component zero (the robot stops on four feet)
Ctrl-C or Ctrl-D        quit (the robot stops first)
======================= =====================================================================
"""

from __future__ import annotations

from dataclasses import dataclass

from wbc.locomotion.gait import VelocityLimits

#: The help lines printed when teleop starts.
KEYS_HELP = ("keys: w/s or up/down forward/back, a/d left/right, q/e or left/right arrows "
             "turn, space or x stop, Ctrl-C quit")
#: Escape sequences of the arrow keys (ANSI, and the application-mode form) -> key names.
_ARROWS = {b"\x1b[A": "up", b"\x1b[B": "down", b"\x1b[C": "right", b"\x1b[D": "left",
           b"\x1bOA": "up", b"\x1bOB": "down", b"\x1bOC": "right", b"\x1bOD": "left"}
#: Key -> (component, steps): component 0 forward, 1 lateral, 2 yaw rate.
_STEPS = {"w": (0, 1), "up": (0, 1), "s": (0, -1), "down": (0, -1), "a": (1, 1), "d": (1, -1),
          "q": (2, 1), "left": (2, 1), "e": (2, -1), "right": (2, -1)}
_STOP, _QUIT = frozenset((" ", "x")), frozenset(("\x03", "\x04"))


def key_names(data: bytes) -> list[str]:
    """The keys in ``data`` as read from the terminal: arrow sequences as ``up``, ``down``,
    ``left``, ``right``, other bytes as their lower-case character (an unknown escape
    sequence as ``esc`` and its characters)."""
    keys: list[str] = []
    i = 0
    while i < len(data):
        arrow = _ARROWS.get(data[i:i + 3])
        if arrow is not None:
            keys.append(arrow)
            i += 3
            continue
        keys.append("esc" if data[i] == 0x1B else chr(data[i]).lower())
        i += 1
    return keys


@dataclass
class KeyTeleop:
    """The command the keys have set.

    Attributes:
        limits: The walking limits each component stays within.
        steps: One key press's step of each component: forward, lateral [m/s], yaw [rad/s].
        command: The command now: forward, lateral [m/s], yaw rate [rad/s].
        quit: A quit key was pressed.
    """

    limits: VelocityLimits
    steps: tuple[float, float, float] = (0.1, 0.1, 0.2)
    command: tuple[float, float, float] = (0.0, 0.0, 0.0)
    quit: bool = False

    def handle(self, data: bytes) -> bool:
        """Apply the keys in ``data``; whether teleop goes on (``False`` after a quit key)."""
        for key in key_names(data):
            if self.quit:
                break  # keys after a quit key change nothing
            self.press(key)
        return not self.quit

    def press(self, key: str) -> None:
        """Apply one key (:func:`key_names`' name); unknown keys change nothing."""
        if key in _QUIT:
            self.quit = True
            self.command = (0.0, 0.0, 0.0)
        elif key in _STOP:
            self.command = (0.0, 0.0, 0.0)
        elif key in _STEPS:
            axis, sign = _STEPS[key]
            limit = (self.limits.forward_mps, self.limits.lateral_mps,
                     self.limits.yaw_rate_radps)[axis]
            values = list(self.command)
            # Rounded to the step's grid: a hundred presses do not drift off it.
            value = round((values[axis] + sign * self.steps[axis]) / self.steps[axis])
            values[axis] = max(-limit, min(limit, round(value * self.steps[axis], 9)))
            values[axis] = 0.0 if values[axis] == 0.0 else values[axis]  # no -0.0
            self.command = (values[0], values[1], values[2])
