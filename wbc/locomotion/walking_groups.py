"""The walking tick's compiled kernel's arguments, in named groups (no compiled code here).

:mod:`wbc.locomotion.walking_kernels` takes the controller's kinematics (:class:`Measured`),
the task references it writes (:class:`Targets`), the walk's parameters and its state: two
one-element records of named fields (:data:`PARAMS_DTYPE`, :data:`STATE_DTYPE`), each one
array crossing the call (a record passed as ``record[0]``, a NumPy void, is unboxed field by
field: measured at 4 us a call, against 0.5 us for the one-element array). The groups are
built once, at :meth:`wbc.locomotion.Walking.start`, of arrays then only updated in place.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from wbc.locomotion.walk_phase import LegState

#: A leg's mode in ``STATE_DTYPE.mode``: :class:`LegState`'s values.
STANCE, UNLOADING, SWING, LATE = (LegState.STANCE.value, LegState.UNLOADING.value,
                                  LegState.SWING.value, LegState.LATE.value)

#: What the tick asks of the state machine for a leg (``STATE_DTYPE.events``):
#: nothing; a stance leg in its unload window (unload it unless its bound is ramping); an
#: unloading leg to load again (a stop); an unloading leg's lift-off time; a swinging or late
#: foot landed; a foot past its touch-down time still up (late); a foot target refused (not
#: finite: the controller's own setter is called with it, and raises naming it).
EV_NONE, EV_UNLOAD, EV_RELOAD, EV_LIFT_OFF, EV_TOUCH_DOWN, EV_LATE, EV_REFUSED = range(7)
#: The tick's return: nothing to do, some leg has an event, the CoM target refused (not
#: finite; nothing after it was done).
TICK_QUIET, TICK_EVENTS, TICK_COM_REFUSED = 0, 1, 2


class Measured(NamedTuple):
    """The controller's kinematics at the last state (its own arrays, read where they are):
    CoM position (3,) [m] and velocity (3,) [m/s], base rotation (3, 3) and position (3,),
    the generalized velocity (nv,), the frames' positions (nf, 3) [m], feet first."""

    com_position: np.ndarray
    com_velocity: np.ndarray
    base_rotation: np.ndarray
    base_position: np.ndarray
    v: np.ndarray
    frame_position: np.ndarray


class Targets(NamedTuple):
    """The task arrays the tick writes (the tasks' own): the CoM task's references (3, 3:
    target, velocity, feed-forward), the base task's target rotation (3, 3) and references
    (3, 3), and each foot task's references (3, 3), ``LEGS`` order."""

    com: np.ndarray
    base_rotation: np.ndarray
    base_reference: np.ndarray
    feet: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


#: The walk's constants, set at its start: the gait's timing [s] and shape [m], the unload
#: window's start (share of the cycle), the foothold rule's gain [s] and largest step [m],
#: the CoM's and the base's heights [m] above the ground, the control period [s], each leg's
#: phase offset (share of the cycle), nominal foot offset from the CoM (heading frame, x, y)
#: [m] and shoulder in the base frame [m].
PARAMS_DTYPE = np.dtype([
    ("period_s", np.float64), ("duty_factor", np.float64), ("swing_s", np.float64),
    ("stance_s", np.float64), ("swing_height_m", np.float64),
    ("touchdown_press_m", np.float64), ("window", np.float64), ("feedback_gain", np.float64),
    ("max_step_m", np.float64), ("com_height_m", np.float64), ("base_height_m", np.float64),
    ("control_period_s", np.float64), ("offsets", np.float64, (4,)),
    ("nominal", np.float64, (4, 2)), ("shoulder", np.float64, (4, 3)),
], align=True)

#: The walk's state, updated every tick: the gait clock [s], the path walked [m], the
#: height trim [m], the yaw reference and the yaw now [rad], the stop's request time [s] and
#: whether the stepping has ended (1); the measured and the commanded velocity (forward, lateral
#: [m/s], yaw rate [rad/s], heading frame); the CoM reference [m] and its velocity [m/s],
#: the command in the world (x, y) [m/s]; per leg: mode (``STANCE``...), the cycle it last
#: unloaded in, its cycle now, this tick's event (``EV_*``), lift-off point, foothold, ground
#: height and last seen height [m] (and whether seen: 1), a late foot's target [m] and time
#: late [s], and the references last computed (3, 3: position, velocity, acceleration).
STATE_DTYPE = np.dtype([
    ("gait_time_s", np.float64), ("distance_m", np.float64), ("trim", np.float64),
    ("yaw_ref", np.float64), ("yaw_now", np.float64), ("stop_s", np.float64),
    ("planted", np.int64), ("measured_velocity", np.float64, (3,)),
    ("commanded_velocity", np.float64, (3,)), ("com_ref", np.float64, (3,)),
    ("com_velocity", np.float64, (3,)), ("cmd_world", np.float64, (2,)),
    ("mode", np.int64, (4,)), ("lifted", np.int64, (4,)), ("cycle", np.int64, (4,)),
    ("events", np.int64, (4,)), ("starts", np.float64, (4, 3)),
    ("footholds", np.float64, (4, 3)), ("ground", np.float64, (4,)),
    ("foot_z", np.float64, (4,)), ("foot_seen", np.int64, (4,)),
    ("late_target", np.float64, (4, 3)), ("late_s", np.float64, (4,)),
    ("path", np.float64, (4, 3, 3)),
], align=True)
