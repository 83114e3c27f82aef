"""Which motor command the simulated GO2's drivers apply at each physics step: :class:`CommandSlot`.

The bridge (:class:`sim.dds_bridge.DdsBridge`) takes the newest valid ``LowCmd_`` at every
physics step and hands it here; the slot decides what the drivers apply, in three modes:

``stand``
    Before the first valid command, the robot holds its start pose with the bridge's own
    joint PD, :data:`STAND_KP` = 60 N m/rad and :data:`STAND_KD` = 5 N m s/rad, no
    feed-forward torque, as a real GO2 stands under Unitree's sport mode until a low-level
    controller takes over. These gains hold the standing pose on every plant preset at 1 kHz
    physics: the base settles 14 mm below the pose, no joint more than 0.1 rad from its
    target (gravity, with no compensation), without oscillating.
``command``
    The newest valid command, from the physics step it is taken at (after ``delay_steps``
    when a transport delay is simulated) and at every step after it until a newer one comes:
    motor drivers keep their last command. Commands are never queued: a newer one replaces
    the older, and a delay line holds at most one command per physics step in flight.
``damping``
    No valid command for :data:`DEFAULT_COMMAND_TIMEOUT_S` (or the given timeout): every
    motor goes to damping, ``kp = 0``, ``kd =`` :data:`DAMPING_KD` = 5 N m s/rad,
    ``tau = 0``. The robot sits down slowly on its belly instead of holding a stale command
    or going limp. Measured from standing (1 kHz physics, each plant preset): the base sinks
    at most 0.32 to 0.46 m/s (limp, kd = 0, it would fall at 2.5 m/s by the ground; kd = 2
    gives 0.5 to 0.8 m/s) and every velocity is below 0.05 rad/s or m/s within 2 to 4 s,
    lying at 0.085 m. The next valid command is applied again at once, from the step it is
    taken at: a controller that restarts takes over without a reset.

Why 0.1 s: a command is due every 2 ms at 500 Hz, so 0.1 s is 50 missed commands, five times
the longest pause a healthy Python controller has here (a full garbage collection, ~20 ms;
DDS round trips are 1 to 7 ms at p99), so the timeout does not trip on a controller that is
merely jittery. It is short enough that a stale command acts briefly: in 0.1 s an
unsupported base falls at most g t^2 / 2 = 49 mm. Longer timeouts let a dead controller's
last torques act for longer; much shorter ones damp the robot under a controller that only
hiccuped. A timeout is measured on the clock the slot is given (the wall clock in the
bridge), from the step the last valid command was applied.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.robot_io.motor_command import MotorCommand

#: The modes, in the order a run meets them.
STAND, COMMAND, DAMPING = "stand", "command", "damping"
#: The stand PD's gains [N m/rad], [N m s/rad] before the first command.
STAND_KP, STAND_KD = 60.0, 5.0
#: The damping gain [N m s/rad] after the command timeout (``kp = 0``, ``tau = 0``).
DAMPING_KD = 5.0
#: Time without a valid command [s] after which the motors go to damping (see the module
#: docstring for the choice).
DEFAULT_COMMAND_TIMEOUT_S = 0.1
#: The longest command timeout [s] accepted.
MAX_COMMAND_TIMEOUT_S = 10.0
#: The longest transport delay, in physics steps.
MAX_DELAY_STEPS = 100


class CommandSlot:
    """Chooses the drivers' command each physics step: stand, the newest command, or damping.

    Args:
        stand_q: The stand PD's joint targets [rad] (12,), in the drivers' joint order;
            ``None``: no torque before the first command (Unitree's simulators).
        timeout_s: Time without a valid command [s] before damping, in (0, 10]; ``None``:
            never, the last command is held (Unitree's simulators).
        delay_steps: Physics steps between taking a command and applying it (a transport
            delay), in [0, 100].

    Raises:
        ConfigurationError: A value out of its range, or ``stand_q`` not 12 finite numbers.
    """

    def __init__(self, stand_q: np.ndarray | None, *,
                 timeout_s: float | None = DEFAULT_COMMAND_TIMEOUT_S, delay_steps: int = 0):
        q = np.zeros(12) if stand_q is None else np.array(stand_q, dtype=np.float64)
        if q.shape != (12,) or not np.isfinite(q).all():
            raise ConfigurationError(
                f"stand_q: expected 12 finite joint angles [rad], received {stand_q!r}")
        self.timeout_s = math.inf if timeout_s is None else as_float(
            "timeout_s", timeout_s, low=0.0, high=MAX_COMMAND_TIMEOUT_S, low_inclusive=False)
        if isinstance(delay_steps, bool) or not isinstance(delay_steps, int) or not (
                0 <= delay_steps <= MAX_DELAY_STEPS):
            raise ConfigurationError(
                f"delay_steps: expected a whole number in [0, {MAX_DELAY_STEPS}], received "
                f"{delay_steps!r}")
        self.delay_steps = delay_steps
        zeros = np.zeros(12)
        #: The stand PD's command (joint targets, :data:`STAND_KP`, :data:`STAND_KD`), or
        #: no torque at all without ``stand_q``.
        gain = 0.0 if stand_q is None else 1.0
        self.stand = MotorCommand(q_des=q, dq_des=zeros.copy(), kp=np.full(12, gain * STAND_KP),
                                  kd=np.full(12, gain * STAND_KD), tau_ff=zeros.copy())
        #: The damping command (``kp = 0``, ``kd =`` :data:`DAMPING_KD`, ``tau = 0``).
        self.damping = MotorCommand(q_des=zeros.copy(), dq_des=zeros.copy(), kp=zeros.copy(),
                                    kd=np.full(12, DAMPING_KD), tau_ff=zeros.copy())
        #: The mode now: :data:`STAND`, :data:`COMMAND` or :data:`DAMPING`.
        self.mode = STAND
        #: ``(from, to)`` when the last :meth:`step` changed the mode, else ``None``.
        self.transition: tuple[str, str] | None = None
        #: Commands applied (taken, and through the delay line).
        self.applied = 0
        #: Times the timeout sent the motors to damping.
        self.timeouts = 0
        self._command: MotorCommand = self.stand
        self._last_s = 0.0
        self._line: deque[MotorCommand | None] = deque()

    @property
    def in_flight(self) -> int:
        """Commands taken but not applied yet (in the delay line)."""
        return sum(command is not None for command in self._line)

    @property
    def command(self) -> MotorCommand:
        """The command the drivers apply now."""
        return {STAND: self.stand, COMMAND: self._command, DAMPING: self.damping}[self.mode]

    def step(self, newest: MotorCommand | None, *, now_s: float) -> MotorCommand:
        """The drivers' command for this physics step.

        Args:
            newest: The newest valid command taken at this step (``None``: none came). It is
                kept, not copied: the caller hands a new object each time.
            now_s: The clock now [s] (for the timeout).
        """
        if self.delay_steps:
            self._line.append(newest)
            newest = self._line.popleft() if len(self._line) > self.delay_steps else None
        before = self.mode
        if newest is not None:
            self._command = newest
            self._last_s = now_s
            self.applied += 1
            self.mode = COMMAND
        elif self.mode == COMMAND and now_s - self._last_s > self.timeout_s:
            self.mode = DAMPING
            self.timeouts += 1
        self.transition = None if self.mode == before else (before, self.mode)
        return self.command
