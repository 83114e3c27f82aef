"""What a DDS bridge of the simulated GO2 runs with: :class:`BridgeConfig`, checked on creation."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from functools import cached_property

from sim.command_slot import DEFAULT_COMMAND_TIMEOUT_S, MAX_COMMAND_TIMEOUT_S, MAX_DELAY_STEPS
from sim.plant import DEFAULT_PLANT, PLANT_PRESETS, Plant
from sim.sensor_model import DEFAULT_SENSORS, SENSOR_PRESETS, SensorModel
from sim.state_framing import FRAMINGS, GO2
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.robot_io.dds.domain_config import check_domain_id, check_interface

#: The physics timestep [s]: 1 kHz, the rate unitree_mujoco's bridge applies commands at.
PHYSICS_TIMESTEP_S = 1e-3
#: The bridge's default: domain 1 on the loopback interface (what unitree_mujoco's configs
#: also use; the framing, not the domain, tells a GO2 from Unitree's simulators).
DEFAULT_DOMAIN_ID, DEFAULT_INTERFACE = 1, "lo"
#: ``LowState_`` rate [Hz] unless told: the rate the GO2's low level is usually run at.
DEFAULT_RATE_HZ = 500.0
#: The poses the robot may start in (and stand in before the first command).
BRIDGE_POSES = ("standing", "lying")


@dataclass(frozen=True)
class BridgeConfig:
    """A bridge's DDS domain, rates, plant, sensors and command handling.

    Attributes:
        domain_id: The DDS domain, 0 to 232 (1 by default, as unitree_mujoco's configs; a
            GO2 uses 0).
        interface: The network interface the domain is bound to (``lo``: this host only).
        rate_hz: ``LowState_`` rate [Hz], a whole number of 1 ms physics steps a period
            (1000, 500, 250, 200, ... 1).
        plant: The plant's physics: a preset name or a :class:`sim.plant.Plant`.
        sensors: What the robot measures: a preset name or a
            :class:`sim.sensor_model.SensorModel`.
        sensor_seed: Seed of the sensors' noise and biases.
        command_delay_s: Time [s] between taking a command and applying it, a whole number
            of physics steps, at most 0.1 s.
        command_timeout_s: Time [s] without a valid command before the motors go to damping
            (:mod:`sim.command_slot`), in (0, 10].
        pose: The pose the robot starts and stands in (:data:`BRIDGE_POSES`).
        viewer: Open the MuJoCo viewer.
        log_truth: Keep every published truth sample (:attr:`DdsBridge.truth_log`).
        framing: How states are framed and commands applied: a GO2's, or one of Unitree's
            simulators' (:mod:`sim.state_framing`).

    Raises:
        ConfigurationError: A field out of its range or unknown, named with what is valid.
    """

    domain_id: int = DEFAULT_DOMAIN_ID
    interface: str = DEFAULT_INTERFACE
    rate_hz: float = DEFAULT_RATE_HZ
    plant: Plant | str = DEFAULT_PLANT
    sensors: SensorModel | str = DEFAULT_SENSORS
    sensor_seed: int = 0
    command_delay_s: float = 0.0
    command_timeout_s: float = DEFAULT_COMMAND_TIMEOUT_S
    pose: str = "standing"
    viewer: bool = False
    log_truth: bool = False
    framing: str = GO2

    def __post_init__(self) -> None:
        check_domain_id(self.domain_id)
        check_interface(self.interface)
        self.steps_per_state  # noqa: B018  (checked: the rate)
        self.plant_model  # noqa: B018
        self.sensor_model  # noqa: B018
        seed = self.sensor_seed
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**31:
            raise ConfigurationError(
                f"sensor_seed: expected a whole number in [0, {2**31 - 1}], received {seed!r}")
        self.delay_steps  # noqa: B018
        as_float("command_timeout_s", self.command_timeout_s, low=0.0,
                 high=MAX_COMMAND_TIMEOUT_S, low_inclusive=False)
        _one_of("pose", self.pose, BRIDGE_POSES)
        _one_of("framing", self.framing, FRAMINGS)
        for name in ("viewer", "log_truth"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigurationError(
                    f"{name}: expected true or false, received {getattr(self, name)!r}")

    @property
    def physics_timestep_s(self) -> float:
        """The physics timestep [s] (:data:`PHYSICS_TIMESTEP_S`)."""
        return PHYSICS_TIMESTEP_S

    @cached_property
    def steps_per_state(self) -> int:
        """Physics steps between two ``LowState_`` messages.

        Raises:
            ConfigurationError: A rate whose period is not a whole number of physics steps.
        """
        return steps_per_state(self.rate_hz)

    @cached_property
    def delay_steps(self) -> int:
        """The command delay in physics steps.

        Raises:
            ConfigurationError: Not a whole number of physics steps, or more than 100.
        """
        delay = as_float("command_delay_s", self.command_delay_s, low=0.0,
                         high=MAX_DELAY_STEPS * PHYSICS_TIMESTEP_S)
        steps = round(delay / PHYSICS_TIMESTEP_S)
        if abs(steps * PHYSICS_TIMESTEP_S - delay) > 1e-9:
            raise ConfigurationError(
                f"command_delay_s: expected a whole number of {PHYSICS_TIMESTEP_S:g} s physics "
                f"steps (e.g. 0.002, 0.009), received {delay:g}")
        return steps

    @cached_property
    def plant_model(self) -> Plant:
        """The plant (the preset's, or the one given)."""
        if isinstance(self.plant, Plant):
            return self.plant
        if not isinstance(self.plant, str):
            raise ConfigurationError(
                f"plant: expected a preset's name or a Plant, received {self.plant!r}")
        return Plant.preset(_one_of("plant", self.plant, PLANT_PRESETS))

    @cached_property
    def sensor_model(self) -> SensorModel:
        """The sensor model (the preset's, or the one given)."""
        if isinstance(self.sensors, SensorModel):
            return self.sensors
        if not isinstance(self.sensors, str):
            raise ConfigurationError(
                f"sensors: expected a preset's name or a SensorModel, received {self.sensors!r}")
        return SensorModel.preset(_one_of("sensors", self.sensors, SENSOR_PRESETS))


def steps_per_state(rate_hz: float) -> int:
    """The physics steps of :data:`PHYSICS_TIMESTEP_S` in one period of ``rate_hz``.

    Raises:
        ConfigurationError: A rate outside [1, 1000] Hz, or whose period is not a whole
            number of physics steps (the message lists valid rates).
    """
    top = 1.0 / PHYSICS_TIMESTEP_S
    rate = as_float("rate_hz", rate_hz, low=1.0, high=top)
    steps = round(top / rate)
    if abs(steps / top - 1.0 / rate) > 1e-9:
        valid = ", ".join(f"{top / n:g}" for n in (1, 2, 4, 5, 8, 10))
        raise ConfigurationError(
            f"rate_hz: expected {top:g} Hz divided by a whole number (the physics runs at "
            f"{top:g} Hz: {valid}, ...), received {rate:g}")
    return steps


def _one_of(field: str, value: object, valid: Iterable[str]) -> str:
    """``value`` if it is one of ``valid``, else a :class:`ConfigurationError` naming ``field``."""
    names = list(valid)
    if not isinstance(value, str) or value not in names:
        raise ConfigurationError(
            f"{field}: expected one of {', '.join(names)}, received {value!r}")
    return value
