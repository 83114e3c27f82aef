"""The estimators' compiled kernels' arguments, in named groups (no compiled code here).

Every estimator's tick takes the same groups: the :class:`Sample`, the contact schedule,
its parameters and work arrays (records of named fields:
:mod:`wbc.core.kernel_records`), the :class:`Legs`' kinematics, its filter's arrays, the
:class:`SensorState` and the :class:`Outputs`. The groups of arrays are built once, at the
estimator's construction, of arrays that are then only updated in place; the sample is the
caller's record's arrays, gathered per call.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from wbc.model.leg_kinematics import LegKinematics

#: ``SensorState.clock``'s entries: the last sample's tick and stamp [s], the time without a
#: trusted sample [s], and the time predicted since the last sample [s].
CLOCK_TICK, CLOCK_STAMP_S, CLOCK_UNTRUSTED_S, CLOCK_PREDICTED_S = 0, 1, 2, 3
CLOCK_SIZE = 4


class Sample(NamedTuple):
    """One tick's sample: whether one came, its counter and stamp [s], and its readings
    (a :class:`wbc.SensorRecord`'s arrays, description order, read where they are)."""

    fresh: bool
    tick: float
    stamp_s: float
    quaternion: np.ndarray
    gyroscope: np.ndarray
    accelerometer: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    foot_force: np.ndarray


#: A sample's scalars as the one compiled call reads them (``header``, :data:`HEADER_SIZE`):
#: whether it came (1 or 0), its counter and its stamp [s].
HEADER_FRESH, HEADER_TICK, HEADER_STAMP_S = 0, 1, 2
HEADER_SIZE = 3


class Readings(NamedTuple):
    """A :class:`Sample`'s arrays alone (a :class:`wbc.SensorRecord`'s): with a header of
    its scalars, the form in which the estimator's one compiled call, whose arrays are read
    from a table of addresses, takes the sample."""

    quaternion: np.ndarray
    gyroscope: np.ndarray
    accelerometer: np.ndarray
    q: np.ndarray
    dq: np.ndarray
    foot_force: np.ndarray


class Legs(NamedTuple):
    """The legs' model and kinematics (:class:`LegKinematics`' arrays: the model, then the
    outputs every tick refills)."""

    imu_offset: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray
    axes: np.ndarray
    foot_offsets: np.ndarray
    foot_position: np.ndarray
    foot_jacobian: np.ndarray
    foot_angular_jacobian: np.ndarray

    @classmethod
    def of(cls, legs: LegKinematics) -> Legs:
        """The group of ``legs``' own arrays (not copies)."""
        return cls(legs.imu_offset, legs.rotations, legs.translations, legs.axes,
                   legs.foot_offsets, legs.foot_position, legs.foot_jacobian,
                   legs.foot_angular_jacobian)


class SensorState(NamedTuple):
    """What the estimator keeps of its sensors between ticks (in/out).

    ``clock`` (:data:`CLOCK_SIZE`) at the ``CLOCK_*`` entries; per foot (``LEGS`` order):
    the sensor's contact verdict (0 or 1), how long it has repeated one reading [s], how
    long it has read well since a fault [s], the fault (``FOOT_*``), its last reading; and
    ``foot_cal``, the calibration and the weight check laid out as
    :data:`wbc.estimation.shared_kernels.CAL_SIZE` says.
    """

    clock: np.ndarray
    foot_contact: np.ndarray
    foot_same_s: np.ndarray
    foot_good_s: np.ndarray
    foot_reason: np.ndarray
    foot_last: np.ndarray
    foot_cal: np.ndarray


class Outputs(NamedTuple):
    """What a tick writes for the controller: the joints kept (the last usable ones)
    [rad], [rad/s], the estimate's ``q`` (19,) and ``v`` (18,), each foot's contact
    weight (4,)."""

    joint_q: np.ndarray
    joint_dq: np.ndarray
    q: np.ndarray
    v: np.ndarray
    contact: np.ndarray


#: The work arrays every estimator's work record has (the shared kernels use them), by
#: name and shape: the legs' kinematics scratch; each foot relative to the IMU (world
#: orientation) [m], the IMU velocity its rolling implies [m/s] and its centre's rolling
#: velocity [m/s]; :func:`foot_motion`'s, :func:`write_outputs`' and :func:`start_pose`'s
#: scratch.
SHARED_WORK: dict[str, tuple[int, ...]] = {
    "legs": (4, 3, 3), "relative": (4, 3), "velocity": (4, 3), "rolling": (4, 3),
    "foot_body": (3,), "foot_spin": (3,), "foot_relative_velocity": (3,),
    "foot_world_spin": (3,), "output_offset": (3,), "output_spin": (3,),
    "output_base": (3,), "start_measured": (4,), "start_rotation": (3, 3),
}
