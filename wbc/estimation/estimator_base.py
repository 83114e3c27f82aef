"""What the estimators share: their inputs, the foot sensors' state, the trust clock, the
bound compiled tick, the start and the fault text (:class:`EstimatorBase`).

The linear Kalman filter (:class:`wbc.estimation.linear_kalman_filter.LinearKalmanFilter`)
and the invariant EKF (:class:`wbc.estimation.invariant_ekf.InvariantEkf`) derive from it.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Any, ClassVar

import numpy as np

from wbc.core.compiled_call import bind_compiled
from wbc.core.compiled_program import CompiledProgram
from wbc.core.conventions import GRAVITY_M_S2
from wbc.core.errors import ConfigurationError
from wbc.core.kernel_records import work_record
from wbc.core.validation import as_float
from wbc.estimation.estimator_config import SensorTrustConfig
from wbc.estimation.estimator_start import floor_shift, start_attitude, start_problem
from wbc.estimation.foot_force_calibration import FootForceCalibration
from wbc.estimation.kernel_groups import (
    CLOCK_PREDICTED_S,
    CLOCK_SIZE,
    CLOCK_STAMP_S,
    CLOCK_TICK,
    CLOCK_UNTRUSTED_S,
    HEADER_FRESH,
    HEADER_SIZE,
    HEADER_STAMP_S,
    HEADER_TICK,
    Legs,
    Outputs,
    Readings,
    Sample,
    SensorState,
)
from wbc.estimation.shared_kernels import (
    CAL_ACTIVE,
    CAL_GAIN,
    CAL_OFFSET,
    CAL_SIZE,
    CAL_SUM,
    CAL_WEIGHT,
)
from wbc.estimation.state_estimate import FOOT_OK, UNTRUSTED, StateEstimate, describe_faults
from wbc.model.description import Go2Description
from wbc.model.leg_kinematics import LegKinematics
from wbc.robot_io.sensor_record import SensorRecord, check_description_orders


def sample_values(fresh: bool, record: SensorRecord) -> tuple[Any, ...]:
    """The values of the kernels' :class:`Sample` of ``record`` (its own arrays), in the
    order of its fields: ``Sample(*sample_values(...))`` is the group.

    The tick passes this plain tuple to the kernel's bound overload for :class:`Sample`,
    whose entry point unboxes a tuple by position: building the ``NamedTuple`` itself every
    tick (its Python ``__new__``) cost 0.3 to 0.9 us more on the 2-core test machine.
    """
    return (fresh, float(record.tick), record.stamp_s, record.imu_quaternion_wxyz,
            record.gyroscope_rad_s, record.accelerometer_m_s2, record.q, record.dq,
            record.foot_force)


class EstimatorBase:
    """What the estimators share: their inputs, the foot sensors' state, the clock, the
    bound compiled tick, :meth:`reset` and :meth:`update`.

    A subclass names its config class (``config_class``), its compiled tick (``kernel``),
    start (``start_kernel``) and work arrays (``work_shapes``), and gives
    :meth:`_filter_arrays`: its filter's arrays, a named group both kernels take. The
    kernels' arguments are named groups (:mod:`wbc.estimation.kernel_groups`), built once
    here of arrays that are then only updated in place.

    Args:
        config: Every number (the config class's defaults when ``None``).
        description: The robot (its legs, feet and IMU frame); the installed GO2 by default.
        control_period_s: The time [s] between samples when their stamps do not say.
        **overrides: Fields of the config to change.
    """

    config_class: ClassVar[type[SensorTrustConfig]] = SensorTrustConfig
    #: ``kernel(sample, schedule, params, legs, filter, sensors, outputs, work)``: one tick;
    #: returns the fault flags.
    kernel: ClassVar[Any] = None
    #: ``header_kernel(header, readings, schedule, ...)``: ``kernel`` on the sample of a
    #: header of its scalars and its :class:`Readings` (the one compiled call's form;
    #: ``None``: every tick through ``kernel``).
    header_kernel: ClassVar[Any] = None
    #: ``start_kernel(quaternion, joint_q, params, legs, filter, base_x, base_y, keep_yaw,
    #: work)``: the filter on four loaded feet, at rest (a ``staticmethod``).
    start_kernel: ClassVar[Any] = None
    #: What the estimator does without the IMU's quaternion (the fault text says it).
    quaternion_note: ClassVar[str] = "orientation from the gyroscope"
    #: The kernels' work arrays, by name and shape (one work record).
    work_shapes: ClassVar[dict[str, tuple[int, ...]]] = {}
    #: It cannot start without the IMU's quaternion (else: roll, pitch from the accelerometer).
    needs_quaternion_to_start: ClassVar[bool] = False

    def __init__(self, config: SensorTrustConfig | None = None, *,
                 description: Go2Description | None = None, control_period_s: float = 1e-3,
                 **overrides: Any):
        base = config or self.config_class()
        unknown = sorted(set(overrides) - set(self.config_class.field_names()))
        if unknown:
            raise ConfigurationError(
                f"unknown estimator parameter(s) {unknown}; valid parameters: "
                f"{', '.join(self.config_class.field_names())}")
        self.config = replace(base, **overrides)
        self.control_period_s = as_float("control_period_s", control_period_s, low=0.0,
                                         high=0.1, low_inclusive=False)
        self.legs = LegKinematics(description)
        self._legs = Legs.of(self.legs)
        self.estimate = StateEstimate()
        self._params = self.config.kernel_params(self.control_period_s)
        #: The ``CLOCK_*`` entries (:mod:`wbc.estimation.kernel_groups`).
        self._clock = np.zeros(CLOCK_SIZE)
        self._clock[CLOCK_TICK] = -1.0
        self._foot_contact = np.ones(4)
        self._foot_same_s = np.zeros(4)
        self._foot_good_s = np.zeros(4)
        self._foot_reason = np.zeros(4, dtype=np.int64)
        self._foot_last = np.full(4, np.nan)
        self._foot_cal = np.zeros(CAL_SIZE)
        robot = description or Go2Description.default()
        self._foot_cal[CAL_WEIGHT] = robot.total_mass * GRAVITY_M_S2
        self.set_foot_calibration(self.config.foot_calibration())
        self._joint_q = np.zeros(12)
        self._joint_dq = np.zeros(12)
        self._work = work_record(self.work_shapes)
        #: The last sample that came (the fault text quotes its readings).
        self._input = SensorRecord.zeros()
        self._schedule = np.zeros(4)
        self._fresh = False  # the last tick had a sample
        self._described = 0  # the flags the estimate's ``faults`` text describes
        self._tick: Any = None
        # The tick as one compiled call bound to a record's arrays (:meth:`_bind_program`):
        # the call, its record and arrays, the sample's scalars it reads, the last record.
        self._program: Any = None
        self._program_record: SensorRecord | None = None
        self._program_arrays: tuple[np.ndarray, ...] = ()
        self._header = np.zeros(HEADER_SIZE)
        self._seen_record: SensorRecord | None = None
        self.started = False
        #: Fresh starts after over ``trust_timeout_s`` untrusted (:meth:`update`); what the
        #: last start did without ('' when nothing); the base's place [m] when trust was lost.
        self.restarts, self.start_note, self._lost_xy = 0, "", (0.0, 0.0)

    def _filter_arrays(self) -> tuple[np.ndarray, ...]:
        """The filter's own arrays, the named group its kernels take."""
        raise NotImplementedError

    # -- start ---------------------------------------------------------------------------

    def start_problem(self, record: SensorRecord | None) -> str:
        """Why ``record`` cannot start the estimator ('' when it can): :func:`start_problem`."""
        return start_problem(record, quaternion_tolerance=self.config.quaternion_tolerance,
                             needs_quaternion=self.needs_quaternion_to_start)

    def reset(self, record: SensorRecord, *, base_xy: tuple[float, float] = (0.0, 0.0),
              keep_yaw: bool = False) -> StateEstimate:
        """Start from ``record`` at rest on its feet (:func:`floor_shift`), description order.

        Args:
            record: The first sample (:meth:`start_problem` says what it needs; without a
                unit quaternion: :func:`start_attitude`).
            base_xy: Where the base is in the estimator's world [m] (the origin by default).
            keep_yaw: Keep the IMU's yaw; by default the estimator's world has the base's
                heading at zero.

        Raises:
            ConfigurationError: A record that cannot start the estimator (the field named);
                nothing is changed.
        """
        check_description_orders(record, self, "reset")
        problem = self.start_problem(record)
        if problem:
            raise ConfigurationError(f"cannot start the state estimator: {problem}")
        quat, self.start_note = start_attitude(record, self.config.quaternion_tolerance)
        self.start_kernel(quat, np.asarray(record.q, dtype=float), self._params, self._legs,
                          self._filter_arrays(), float(base_xy[0]), float(base_xy[1]),
                          bool(keep_yaw), self._work)
        self._shift_height(floor_shift(self.foot_positions[:, 2], self.config.foot_radius_m))
        self._foot_contact[:] = 1.0
        self._foot_same_s[:] = 0.0
        self._foot_good_s[:] = 0.0
        self._foot_reason[:] = FOOT_OK
        self._foot_last[:] = np.nan
        self._foot_cal[CAL_WEIGHT + 1:] = 0.0  # the weight check starts afresh
        # The record itself is the first sample.
        clock = self._clock
        clock[CLOCK_TICK] = record.tick - 1
        clock[CLOCK_STAMP_S] = record.stamp_s - self.control_period_s
        clock[CLOCK_UNTRUSTED_S] = clock[CLOCK_PREDICTED_S] = 0.0
        self._described = 0
        self.estimate.faults = ""
        self.estimate.usable = True  # a fresh start: not a return after a gap
        self.started = True
        self._schedule[:] = np.inf  # four loaded feet
        self._bind_program(record)  # here, not inside a later tick: it may load compiled code
        return self.update(record, self._schedule)

    # -- the tick ------------------------------------------------------------------------

    def update(self, record: SensorRecord | None, normal_force_bounds: np.ndarray
               ) -> StateEstimate:
        """One tick: ``record`` (``None`` when no sample arrived) and the contact schedule.

        Args:
            record: This period's sample, description order; ``None`` when none came.
            normal_force_bounds: Each foot's normal-force bound [N] in the controller, in
                ``LEGS`` order (0 for a foot in swing): the contact schedule. A controller
                fills it with ``normal_force_bounds(out)``.

        Returns:
            The estimate (the same object every tick, updated in place).

        Raises:
            ConfigurationError: Not started (call :meth:`reset` first), or a schedule of the
                wrong shape.
        """
        if not self.started:
            raise ConfigurationError(
                f"{type(self).__name__}.update: call reset(record) first")
        if normal_force_bounds is not self._schedule:
            schedule = self._schedule
            try:
                schedule[:] = normal_force_bounds
            except (ValueError, TypeError):
                raise ConfigurationError(
                    f"normal_force_bounds: expected 4 numbers (FL, FR, RL, RR) [N], received "
                    f"{normal_force_bounds!r}") from None
        if record is None:  # the kernel reads nothing of a sample that did not come
            fresh, record = False, self._input
        else:
            check_description_orders(record, self, "update")
            fresh, self._input = True, record
        self._fresh = fresh
        arrays = self._program_arrays
        if (record is self._program_record and record.imu_quaternion_wxyz is arrays[0]
                and record.gyroscope_rad_s is arrays[1]
                and record.accelerometer_m_s2 is arrays[2] and record.q is arrays[3]
                and record.dq is arrays[4] and record.foot_force is arrays[5]):
            header = self._header  # the record's arrays are read where the table points
            header[HEADER_FRESH] = fresh
            header[HEADER_TICK] = record.tick
            header[HEADER_STAMP_S] = record.stamp_s
            flags = self._program()
        else:
            flags = self._bound_tick(fresh, record)
            if record is self._seen_record:  # the same record again: bind the one call to it
                self._bind_program(record)
            self._seen_record = record
        estimate = self.estimate
        was_usable = estimate.usable
        estimate.flags = flags
        estimate.trusted = not flags & UNTRUSTED
        estimate.untrusted_s = float(self._clock[CLOCK_UNTRUSTED_S])
        # (A tolerance for the sum of periods: ten 1 ms ticks are 10 ms, not 10.000000000002.)
        estimate.usable = estimate.untrusted_s <= self.config.trust_timeout_s + 1e-9
        if was_usable and not estimate.usable:
            self._lost_xy = (float(estimate.q[0]), float(estimate.q[1]))
        elif not was_usable and estimate.trusted and not self.start_problem(record):
            # Back after the trust limit: start again here, not integrating across the gap.
            self.restarts += 1
            return self.reset(record, base_xy=self._lost_xy)
        if flags != self._described:  # the text is built when what it says changes
            self._described = flags
            estimate.faults = self.describe(flags)
        return estimate

    def _bound_tick(self, fresh: bool, record: SensorRecord) -> int:
        """The tick through the kernel's bound overload (:meth:`_bind`), the sample's arrays
        unboxed on each call: any record, its arrays replaced or of another type included."""
        if self._tick is None:
            self._tick = self._bind()
        try:
            return int(self._tick(fresh, record))
        except (TypeError, AttributeError):
            if isinstance(record, SensorRecord):  # its arrays were replaced after construction
                record = SensorRecord(**{f.name: getattr(record, f.name)
                                         for f in fields(SensorRecord)})
            else:
                raise ConfigurationError(
                    f"record: expected a SensorRecord or None, received "
                    f"{type(record).__name__}") from None
            self._input = record
            return int(self._tick(fresh, record))

    def _groups(self) -> tuple[Any, ...]:
        """The kernels' groups after the sample, built of the estimator's own arrays."""
        estimate = self.estimate
        return (
            self._schedule, self._params, self._legs, self._filter_arrays(),
            SensorState(self._clock, self._foot_contact, self._foot_same_s, self._foot_good_s,
                        self._foot_reason, self._foot_last, self._foot_cal),
            Outputs(self._joint_q, self._joint_dq, estimate.q, estimate.v, estimate.contact),
            self._work)

    def _bind_program(self, record: SensorRecord) -> None:
        """The tick as one compiled call (:class:`~wbc.core.compiled_program.CompiledProgram`)
        that reads every array, ``record``'s included, from a table of addresses made here:
        numba unboxes one array a call where the bound overload unboxes some thirty (about
        3 us a tick alone, 6 in a running loop, on the 2-core test host). The sample's
        scalars go through :attr:`_header`. A record whose arrays are not float64
        C-contiguous vectors keeps the bound overload."""
        if self.header_kernel is None:
            return
        arrays = (record.imu_quaternion_wxyz, record.gyroscope_rad_s, record.accelerometer_m_s2,
                  record.q, record.dq, record.foot_force)
        if not all(type(a) is np.ndarray and a.dtype == np.float64 and a.ndim == 1
                   and a.flags.c_contiguous for a in arrays):
            return
        program = CompiledProgram([(self.header_kernel,
                                    (self._header, Readings(*arrays), *self._groups()))])
        self._program, self._program_record, self._program_arrays = program.run, record, arrays

    def _bind(self) -> Any:
        """The kernel's compiled overload with the estimator's own groups bound; the
        sample's arrays are gathered per call (read where they are: no copy)."""
        groups = self._groups()
        compiled = bind_compiled(self.kernel, Sample(*sample_values(True, self._input)),
                                 *groups).func
        #: The arrays that cross into compiled code every tick besides the sample's.
        self._tick_arrays = tuple(
            a for group in groups for a in (group if isinstance(group, tuple) else (group,)))

        def tick(fresh: bool, record: SensorRecord) -> int:
            return compiled(sample_values(fresh, record), *groups)

        return tick

    # -- the foot sensors' calibration ---------------------------------------------------

    @property
    def foot_calibration(self) -> FootForceCalibration:
        """The foot sensors' model in use (``counts = offset + gain x N`` per foot)."""
        return self._calibration

    def set_foot_calibration(self, calibration: FootForceCalibration) -> None:
        """Use ``calibration`` from the next tick on (learnt on the robot, or given).

        Raises:
            ConfigurationError: Not a :class:`FootForceCalibration`.
        """
        if not isinstance(calibration, FootForceCalibration):
            raise ConfigurationError(
                f"calibration: expected a FootForceCalibration, received "
                f"{type(calibration).__name__}")
        self._calibration = calibration
        self._foot_cal[CAL_OFFSET:CAL_OFFSET + 4] = calibration.offset
        self._foot_cal[CAL_GAIN:CAL_GAIN + 4] = calibration.gain
        self._foot_cal[CAL_WEIGHT + 1:] = 0.0  # judged afresh on the new calibration

    @property
    def weight_contradicted(self) -> bool:
        """The foot forces contradict the robot's weight: contact is the schedule's alone."""
        return bool(self._foot_cal[CAL_ACTIVE] > 0.0)

    # -- reporting -----------------------------------------------------------------------

    @property
    def last_sample(self) -> SensorRecord | None:
        """The last tick's sample (``None`` if none came; the caller's record, not a copy)."""
        return self._input if self._fresh else None

    @property
    def schedule_input(self) -> np.ndarray:
        """The array :meth:`update` reads the contact schedule from [N] (4,), ``LEGS``
        order: a loop that fills it in place and passes it to :meth:`update` saves a copy."""
        return self._schedule

    @property
    def last_schedule(self) -> np.ndarray:
        """The contact schedule [N] the last tick was given (a copy)."""
        return self._schedule.copy()

    def describe(self, flags: int | None = None) -> str:
        """What the estimator distrusts this tick, in words ('' when nothing), with the
        readings of the last sample that arrived."""
        return describe_faults(self.estimate.flags if flags is None else flags, self._input,
                               self._foot_reason, self.config.quaternion_tolerance,
                               self.config.quaternion_timeout_s, self.quaternion_note,
                               (float(self._foot_cal[CAL_SUM]),
                                float(self._foot_cal[CAL_WEIGHT])))
