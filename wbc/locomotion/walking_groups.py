"""The walking tick's compiled kernel's arguments, in named groups (no compiled code here).

:mod:`wbc.locomotion.walking_kernels` reads the controller's kinematics (:class:`Measured`)
and writes the task references (:class:`Targets`) where they are, and keeps the walk's
parameters and state in two one-element records of named fields (:data:`PARAMS_DTYPE`,
:data:`STATE_DTYPE`). Every array that crosses a compiled call is unboxed on every call: on
this project's 2-core host about 0.2 us an array, 2.8 us of the 3 us a call with the 15
arrays of the two groups took (a record passed as ``record[0]``, a NumPy void, is worse:
4 us). So the two groups cross as one record of their arrays' addresses
(:func:`address_record`, :data:`ADDRESS_DTYPE`), built once at
:meth:`wbc.locomotion.Walking.start` of arrays that are then only updated in place (the
tasks' references cannot be replaced, the kinematics' arrays are views of one record made
once), and kept alive by the walk that holds the groups: the call takes 0.2 us.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from wbc.core.errors import ConfigurationError
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

#: The addresses of the arrays of :class:`Measured` and :class:`Targets` (the data of each,
#: C-contiguous float64): the kinematics' CoM position and velocity (3,), base rotation
#: (3, 3) and position (3,), the base's 6 velocities (the first of ``v``), the feet's
#: positions (the first 4 rows of ``frame_position``, 4 x 3); the CoM task's references
#: (3, 3), the base task's rotation and references (3, 3), each foot task's (3, 3).
ADDRESS_DTYPE = np.dtype([
    ("com_position", np.int64), ("com_velocity", np.int64), ("base_rotation", np.int64),
    ("base_position", np.int64), ("base_velocity", np.int64), ("feet_position", np.int64),
    ("com_reference", np.int64), ("base_rotation_target", np.int64),
    ("base_reference", np.int64), ("foot_references", np.int64, (4,)),
], align=True)


def address_record(measured: Measured, targets: Targets) -> np.ndarray:
    """The one-element :data:`ADDRESS_DTYPE` record of the groups' arrays, after checking
    that each is what the kernel reads or writes there.

    The caller must keep ``measured`` and ``targets`` (their arrays) alive while the record
    is used, and the arrays must not be replaced: the kernel reads and writes where they were.

    Raises:
        ConfigurationError: An array that is not C-contiguous float64 of the shape the
            kernel uses (at least it: 6 of ``v``, 4 rows of ``frame_position``), or a target
            that is not writeable (the group, the field and what it was named).
    """
    record = np.zeros(1, ADDRESS_DTYPE)
    entry = record[0]
    for group, name, array, shape, written in (
            ("Measured", "com_position", measured.com_position, (3,), False),
            ("Measured", "com_velocity", measured.com_velocity, (3,), False),
            ("Measured", "base_rotation", measured.base_rotation, (3, 3), False),
            ("Measured", "base_position", measured.base_position, (3,), False),
            ("Measured", "v", measured.v[:6], (6,), False),
            ("Measured", "frame_position", measured.frame_position[:4], (4, 3), False),
            ("Targets", "com", targets.com, (3, 3), True),
            ("Targets", "base_rotation", targets.base_rotation, (3, 3), True),
            ("Targets", "base_reference", targets.base_reference, (3, 3), True),
            *(("Targets", f"feet[{i}]", foot, (3, 3), True)
              for i, foot in enumerate(targets.feet))):
        if not (isinstance(array, np.ndarray) and array.dtype == np.float64
                and array.shape == shape and array.flags.c_contiguous
                and (array.flags.writeable or not written)):
            raise ConfigurationError(
                f"{group}.{name}: expected a C-contiguous float64 array of shape {shape}"
                f"{' that can be written' if written else ''}, received "
                f"{getattr(array, 'dtype', type(array).__name__)} "
                f"{getattr(array, 'shape', '')}")
    entry["com_position"] = measured.com_position.ctypes.data
    entry["com_velocity"] = measured.com_velocity.ctypes.data
    entry["base_rotation"] = measured.base_rotation.ctypes.data
    entry["base_position"] = measured.base_position.ctypes.data
    entry["base_velocity"] = measured.v.ctypes.data
    entry["feet_position"] = measured.frame_position.ctypes.data
    entry["com_reference"] = targets.com.ctypes.data
    entry["base_rotation_target"] = targets.base_rotation.ctypes.data
    entry["base_reference"] = targets.base_reference.ctypes.data
    entry["foot_references"] = [foot.ctypes.data for foot in targets.feet]
    return record
