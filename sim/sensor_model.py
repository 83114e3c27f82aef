"""What the simulated GO2's sensors are like: :class:`SensorModel`, its noise, biases and scales.

:class:`sim.sensors.SimulatedSensors` samples the plant with one; :data:`SENSOR_PRESETS`
names the usual ones (``go2``, the default, and ``exact``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, check_name, known_fields_only


@known_fields_only("sensor parameter")
@dataclass(frozen=True)
class SensorModel:
    """The simulated GO2's sensors: noise, biases, resolution and scale of each signal.

    Build one from a preset and change any field by name::

        SensorModel.preset("go2").with_params(gyro_noise_rad_s=0.01, foot_force_gain=0.0)

    Attributes:
        name: The preset it came from (``+`` and the changes when changed).
        gyro_noise_rad_s: Gyroscope white noise, standard deviation per sample [rad/s].
        gyro_bias_rad_s: Standard deviation of the gyroscope's starting bias [rad/s].
        gyro_bias_walk: Its random walk [rad/s/sqrt(s)].
        accel_noise_m_s2: Accelerometer white noise per sample [m/s^2].
        accel_bias_m_s2: Standard deviation of its starting bias [m/s^2].
        accel_bias_walk: Its random walk [m/s^2/sqrt(s)].
        attitude_time_constant_s: The robot's attitude filter's roll/pitch correction time
            constant [s]; 0 reports the true orientation.
        joint_position_noise_rad: Joint position white noise [rad].
        joint_position_resolution_rad: The encoders' step at the joint [rad] (0: none).
        joint_velocity_noise_rad_s: Joint velocity white noise [rad/s].
        joint_torque_noise_nm: Estimated joint torque white noise [N m].
        foot_force_offset: A foot sensor's count with no load.
        foot_force_gain: Counts per newton of normal force (0: no foot sensors: a constant
            ``offset``).
        foot_force_noise: White noise of the count.
        foot_force_full_scale: The highest count the sensor reports.
        foot_force_integer: Round the count to an integer (the message's int16).
    """

    name: str = "go2"
    gyro_noise_rad_s: float = 0.004
    gyro_bias_rad_s: float = 2e-4
    gyro_bias_walk: float = 1e-5
    accel_noise_m_s2: float = 0.03
    accel_bias_m_s2: float = 0.02
    accel_bias_walk: float = 1e-4
    attitude_time_constant_s: float = 5.0
    joint_position_noise_rad: float = 5e-5
    joint_position_resolution_rad: float = 3e-5
    joint_velocity_noise_rad_s: float = 0.02
    joint_torque_noise_nm: float = 0.1
    foot_force_offset: float = 10.0
    foot_force_gain: float = 2.5
    foot_force_noise: float = 3.0
    foot_force_full_scale: float = 1000.0
    foot_force_integer: bool = True

    def __post_init__(self) -> None:
        for name, high in _RANGES.items():
            as_float(name, getattr(self, name), low=0.0, high=high)
        if not isinstance(self.foot_force_integer, bool):
            raise ConfigurationError(
                f"foot_force_integer: expected true or false, received "
                f"{self.foot_force_integer!r}")
        if self.foot_force_full_scale <= self.foot_force_offset:
            raise ConfigurationError(
                f"foot_force_full_scale: expected more than foot_force_offset "
                f"({self.foot_force_offset:g}), received {self.foot_force_full_scale:g}")

    @classmethod
    def preset(cls, name: str) -> SensorModel:
        """The named preset (see :data:`SENSOR_PRESETS`)."""
        check_name("sensor preset", name, SENSOR_PRESETS)
        return SENSOR_PRESETS[name]

    @staticmethod
    def parameter_names() -> tuple[str, ...]:
        """Every name :meth:`with_params` takes."""
        return tuple(f.name for f in fields(SensorModel) if f.name != "name")

    def with_params(self, **params: Any) -> SensorModel:
        """This model with fields changed by name; the name records the changes.

        Raises:
            UnknownNameError: A name that is not a field (the message lists them).
            ConfigurationError: A value out of its range (the message gives the range).
        """
        valid = self.parameter_names()
        for key in params:
            check_name("sensor parameter", key, valid)
        if not params:
            return self
        label = ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                          for k, v in params.items())
        return replace(self, name=f"{self.name} + {label}", **params)

    def describe(self) -> str:
        """One line: the preset and its main numbers."""
        if self.is_exact:
            return f"sensors {self.name} (the true state, no noise)"
        return (f"sensors {self.name} (gyro {self.gyro_noise_rad_s:g} rad/s, accel "
                f"{self.accel_noise_m_s2:g} m/s^2, attitude filter "
                f"{self.attitude_time_constant_s:g} s; joints {self.joint_position_noise_rad:g} "
                f"rad / {self.joint_velocity_noise_rad_s:g} rad/s; feet "
                f"{self.foot_force_gain:g} counts/N)")

    @property
    def is_exact(self) -> bool:
        """No noise, bias or quantisation anywhere."""
        return self == replace(SENSOR_PRESETS["exact"], name=self.name)

    def as_dict(self) -> dict[str, Any]:
        """Plain values, JSON-ready."""
        return asdict(self)


#: Upper bounds of the numeric fields (all are >= 0).
_RANGES = {
    "gyro_noise_rad_s": 1.0, "gyro_bias_rad_s": 0.5, "gyro_bias_walk": 0.1,
    "accel_noise_m_s2": 10.0, "accel_bias_m_s2": 2.0, "accel_bias_walk": 1.0,
    "attitude_time_constant_s": 1000.0, "joint_position_noise_rad": 0.5,
    "joint_position_resolution_rad": 0.1, "joint_velocity_noise_rad_s": 50.0,
    "joint_torque_noise_nm": 50.0, "foot_force_offset": 10000.0, "foot_force_gain": 1000.0,
    "foot_force_noise": 10000.0, "foot_force_full_scale": 32767.0,
}

#: The named sensor models. ``go2`` (the default): the GO2's sensors as far as public
#: sources tell, the rest assumed from its class of hardware (docs/state-estimation.md,
#: "The simulated sensors"):
#: gyroscope and accelerometer noise of a BMI088-class MEMS IMU read at about 230 Hz
#: bandwidth (0.014 deg/s/sqrt(Hz) -> 0.004 rad/s; 175 ug/sqrt(Hz) -> 0.03 m/s^2), bias
#: walks as go2_odometry's InEKF assumes for a GO2 (1e-5, 1e-4), starting biases left by a
#: start-up calibration (2e-4 rad/s, 0.02 m/s^2); a 5 s attitude filter; a 15-bit rotor
#: encoder through the 6.33:1 gearbox (3e-5 rad); foot counts of 10 unloaded and 2.5 per
#: newton, so that the thresholds used on GO2s (20 in go2_odometry, 40/60 in Leg-KILO)
#: separate an unloaded foot from one carrying 10 to 20 N. ``exact``: the true state.
SENSOR_PRESETS: dict[str, SensorModel] = {
    "go2": SensorModel(),
    "exact": SensorModel(
        name="exact", gyro_noise_rad_s=0.0, gyro_bias_rad_s=0.0, gyro_bias_walk=0.0,
        accel_noise_m_s2=0.0, accel_bias_m_s2=0.0, accel_bias_walk=0.0,
        attitude_time_constant_s=0.0, joint_position_noise_rad=0.0,
        joint_position_resolution_rad=0.0, joint_velocity_noise_rad_s=0.0,
        joint_torque_noise_nm=0.0, foot_force_noise=0.0, foot_force_integer=False),
}
#: The sensor model every simulation uses unless told otherwise.
DEFAULT_SENSORS = "go2"
