"""The estimators' numbers: what they share (:class:`SensorTrustConfig`) and the linear filter's.

Each estimator's compiled tick reads its config by field name from one parameter record
(:meth:`SensorTrustConfig.kernel_params`): the config class's own ``_PARAMS`` and
:data:`CONTACT_PARAMS` (the shared contact fusion's,
:func:`wbc.estimation.shared_kernels.contact_weights`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.kernel_records import parameter_record
from wbc.core.validation import as_float, known_fields_only
from wbc.estimation.foot_force_calibration import FootForceCalibration
from wbc.model.description import FOOT_RADIUS_M


@dataclass(frozen=True)
class SensorTrustConfig:
    """What every estimator here shares: which readings it trusts, how it weighs the feet.

    Attributes:
        quaternion_tolerance: Largest ``| |quat| - 1 |`` of a quaternion taken as unit.
        quaternion_timeout_s: Time [s] on the gyroscope alone before the orientation is
            no longer trusted (an estimator whose orientation needs no quaternion ignores
            it).
        foot_position_noise_m: Noise of a foot's position from the kinematics [m].
        swing_noise_scale: How much a foot's measurement noise grows at zero contact weight.
        min_contact_weight: Below this weight a foot follows the kinematics freely.
        full_trust_force_n: A stance foot whose normal-force bound [N] is at least this
            has the schedule's full weight (the bound ramps down as a foot is unloaded).
        use_foot_force: Fuse the foot-force sensors with the schedule (off: schedule only,
            for robots or simulators without foot sensors).
        foot_force_offset: Each foot sensor's count with no load: one number for every
            foot or four (FL, FR, RL, RR); see
            :class:`wbc.estimation.foot_force_calibration.FootForceCalibration`. The
            default is the simulated GO2's (``sim.sensor_model``); a robot's is learnt
            on it (:mod:`actions.robot.foot_calibration`) or given.
        foot_force_gain: Each foot sensor's counts per newton of normal force (above 0).
        foot_force_on_n: Normal force [N] above which a foot turns to contact.
        foot_force_off_n: Normal force [N] below which it turns to no contact.
        foot_force_full_scale: The sensor's highest count: a reading there is saturated.
        weight_low_fraction: The feet's calibrated forces summing to less than this
            fraction of the robot's weight while at least three feet stand (or more than
            ``weight_high_fraction`` of it) contradict the weight: a wrong calibration or
            broken sensors, and the schedule alone decides every foot.
        weight_high_fraction: See ``weight_low_fraction``.
        weight_check_s: How long [s] the evidence must contradict the weight before the
            fault is raised (a landing's or a push's peak does not).
        foot_sensor_stuck_s: A stance foot's sensor whose count does not change for this
            long [s] is stuck (a loaded foot's live sensor always changes: its load and its
            noise do).
        foot_sensor_recover_s: It is trusted again after this long [s] of changing,
            in-range readings.
        trust_timeout_s: Time [s] without a trustworthy sample (fresh, finite joints and
            gyroscope) after which the estimate is not usable and the loop sends the
            controller's safe command.
        foot_radius_m: Radius of the foot spheres [m].
    """

    #: Valid range of each of the subclass's own numeric fields (low exclusive unless 0).
    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {}
    #: The numbers the subclass's kernel reads (by name).
    _PARAMS: ClassVar[tuple[str, ...]] = ()

    quaternion_tolerance: float = 0.01
    quaternion_timeout_s: float = 1.0
    foot_position_noise_m: float = 2e-3
    swing_noise_scale: float = 100.0
    min_contact_weight: float = 0.02
    full_trust_force_n: float = 30.0
    use_foot_force: bool = True
    foot_force_offset: tuple[float, float, float, float] | float = 10.0
    foot_force_gain: tuple[float, float, float, float] | float = 2.5
    # 20 / 12 N are the 60 / 40 counts the thresholds were at 10 + 2.5 counts/N.
    foot_force_on_n: float = 20.0
    foot_force_off_n: float = 12.0
    foot_force_full_scale: float = 1000.0
    weight_low_fraction: float = 0.5
    weight_high_fraction: float = 2.0
    weight_check_s: float = 0.1
    foot_sensor_stuck_s: float = 0.05
    foot_sensor_recover_s: float = 0.5
    trust_timeout_s: float = 0.01
    foot_radius_m: float = FOOT_RADIUS_M

    def __post_init__(self) -> None:
        for name, (low, high) in {**_SHARED_RANGES, **self._RANGES}.items():
            as_float(name, getattr(self, name), low=low, high=high, low_inclusive=low == 0.0)
        if not isinstance(self.use_foot_force, bool):
            raise ConfigurationError(
                f"use_foot_force: expected true or false, received {self.use_foot_force!r}")
        calibration = self.foot_calibration()  # checks offset and gain (field, leg named)
        object.__setattr__(self, "foot_force_offset", calibration.offset)
        object.__setattr__(self, "foot_force_gain", calibration.gain)
        if self.foot_force_off_n >= self.foot_force_on_n:
            raise ConfigurationError(
                f"foot_force_off_n: expected less than foot_force_on_n "
                f"({self.foot_force_on_n:g} N), received {self.foot_force_off_n:g}")
        on_counts = calibration.counts(np.full(4, self.foot_force_on_n))
        if np.any(self.foot_force_full_scale <= on_counts):
            raise ConfigurationError(
                f"foot_force_full_scale: expected more than the count at foot_force_on_n "
                f"({np.max(on_counts):g}), received {self.foot_force_full_scale:g}")

    def foot_calibration(self, source: str = "default") -> FootForceCalibration:
        """The foot sensors' model this config gives (``source`` says where it is from)."""
        return FootForceCalibration(offset=self.foot_force_offset, gain=self.foot_force_gain,
                                    source=source)

    @classmethod
    def field_names(cls) -> tuple[str, ...]:
        """Every field's name."""
        return tuple(f.name for f in fields(cls))

    def kernel_params(self, control_period_s: float) -> np.ndarray:
        """The parameter record the compiled kernels read by name: the subclass's
        ``_PARAMS`` and :data:`CONTACT_PARAMS` as float64 (``use_foot_force`` a bool), and
        ``control_period_s`` [s] (the step when the samples' stamps do not give it)."""
        values: dict[str, float | bool] = {
            name: bool(getattr(self, name)) if name == "use_foot_force"
            else float(getattr(self, name)) for name in (*self._PARAMS, *CONTACT_PARAMS)}
        values["control_period_s"] = float(control_period_s)
        return parameter_record(values)


#: The contact fusion's fields, in every estimator's parameter record (the calibration per
#: foot is an array of its own: see ``shared_kernels.CAL_SIZE``).
CONTACT_PARAMS = ("full_trust_force_n", "use_foot_force", "foot_force_on_n",
                  "foot_force_off_n", "foot_force_full_scale", "foot_sensor_stuck_s",
                  "foot_sensor_recover_s", "weight_low_fraction", "weight_high_fraction",
                  "weight_check_s")

#: Valid range of each shared numeric field (a 0 lower bound is inclusive, others exclusive).
_SHARED_RANGES: dict[str, tuple[float, float]] = {
    "quaternion_tolerance": (1e-6, 0.5), "quaternion_timeout_s": (1e-3, 60.0),
    "foot_position_noise_m": (1e-9, 1.0), "swing_noise_scale": (1.0, 1e6),
    "min_contact_weight": (0.0, 1.0), "full_trust_force_n": (1e-3, 1e4),
    "foot_force_on_n": (0.0, 1e4), "foot_force_off_n": (0.0, 1e4),
    "foot_force_full_scale": (-32768.0, 32767.0), "weight_low_fraction": (0.0, 1.0),
    "weight_high_fraction": (1.0, 100.0), "weight_check_s": (1e-3, 10.0),
    "foot_sensor_stuck_s": (1e-3, 10.0),
    "foot_sensor_recover_s": (0.0, 60.0), "trust_timeout_s": (0.0, 10.0),
    "foot_radius_m": (0.0, 0.1),
}


@known_fields_only("estimator parameter")
@dataclass(frozen=True)
class EstimatorConfig(SensorTrustConfig):
    """Every number of the linear estimator, validated (an error names the field and its
    range); the shared ones are :class:`SensorTrustConfig`'s.

    Attributes:
        orientation_time_constant_s: How fast [s] the orientation follows the IMU's
            quaternion (the gyroscope carries it in between).
        gyro_bias_time_constant_s: How fast [s] the gyroscope bias is learnt from it.
        position_process_noise: Random walk of the IMU's position [m/sqrt(s)].
        velocity_process_noise: Of its velocity (what the accelerometer misses)
            [m/s/sqrt(s)].
        foot_process_noise: Of a stance foot's position (slip, rolling the model misses)
            [m/sqrt(s)].
        foot_velocity_noise_m_s: Noise of the body's velocity from a stance foot [m/s].
        foot_height_noise_m: Noise of a stance foot's height above the floor [m].
    """

    _RANGES: ClassVar[dict[str, tuple[float, float]]] = {
        "orientation_time_constant_s": (1e-4, 100.0), "gyro_bias_time_constant_s": (1e-3, 1e4),
        "position_process_noise": (1e-9, 10.0), "velocity_process_noise": (1e-9, 100.0),
        "foot_process_noise": (1e-9, 10.0), "foot_velocity_noise_m_s": (1e-9, 10.0),
        "foot_height_noise_m": (1e-9, 1.0),
    }
    _PARAMS: ClassVar[tuple[str, ...]] = (
        "orientation_time_constant_s", "gyro_bias_time_constant_s", "quaternion_tolerance",
        "quaternion_timeout_s", "position_process_noise", "velocity_process_noise",
        "foot_process_noise", "foot_position_noise_m", "foot_velocity_noise_m_s",
        "foot_height_noise_m", "swing_noise_scale", "min_contact_weight", "foot_radius_m")

    orientation_time_constant_s: float = 0.05
    gyro_bias_time_constant_s: float = 10.0
    position_process_noise: float = 1e-3
    velocity_process_noise: float = 0.1
    foot_process_noise: float = 1e-3
    foot_velocity_noise_m_s: float = 0.03
    foot_height_noise_m: float = 2e-3
