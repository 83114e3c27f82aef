"""The robustness benchmark's plants: :class:`PlantCase` and the rows and sweeps it runs."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

from actions.go2.go2_actions import GO2_ACTIONS, HIGH_FIVE_ACTION
from sim.disturbances import Push
from sim.episode import Episode, episode_default
from sim.plant import Plant
from sim.sensor_faults import SensorFault
from sim.sensor_model import SensorModel
from wbc.controller.controller_config import ControllerConfig


def _default_plant() -> Plant:
    return Plant.preset(episode_default("plant"))


# The Episode defaults a PlantCase starts from, read once (dataclass defaults are constants).
_CONTROL_PERIOD_S: float = episode_default("control_period_s")
_SENSORS: str = episode_default("sensors")
_STATE: str = episode_default("state")
_ESTIMATOR: str = episode_default("estimator")


@dataclass(frozen=True)
class PlantCase:
    """One row of the plant table: a plant, and the sensors and delay between it and the loop.

    The defaults are :class:`sim.episode.Episode`'s.
    """

    name: str = "nominal"
    plant: Plant = field(default_factory=_default_plant)
    #: Control periods between a command and the drivers applying it.
    delay_ticks: int = 0
    #: Control period [s] (1 ms: 1 kHz; 2 ms: 500 Hz).
    control_period_s: float = _CONTROL_PERIOD_S
    #: What the robot measures (a :class:`sim.sensor_model.SensorModel` or a preset's name).
    sensors: SensorModel | str = _SENSORS
    #: Where the controller's state comes from: ``estimate`` (default) or ``truth``.
    state: str = _STATE
    #: Sensor faults, their times counted from the goal's start [s].
    sensor_faults: tuple[SensorFault, ...] = ()
    #: The state estimator (:data:`wbc.estimation.estimators.ESTIMATORS`), when estimating.
    estimator: str = _ESTIMATOR

    def sensor_model(self) -> SensorModel:
        """The sensor model (the preset resolved)."""
        return (SensorModel.preset(self.sensors) if isinstance(self.sensors, str)
                else self.sensors)

    def episode(self, *, height_m: float, hold_s: int, seed: int = 0,
                pushes: tuple[Push, ...] = (), gains: dict[str, Any] | None = None,
                **run: Any) -> Episode:
        """A high five of ``height_m`` [m] held ``hold_s`` [s] on this plant.

        Args:
            height_m, hold_s: The goal.
            seed: Seed of the sensors' noise and biases.
            pushes: Pushes whose ``at_s`` counts from the goal's start [s].
            gains: :class:`wbc.ControllerConfig` parameters of the controller by their bare
                names (a sweep file's ``gains``: ``swing_kp``, not ``shaping.swing_kp``).
            run: More :class:`sim.episode.Episode` fields (``after_s``, ``timeout_s``...).
        """
        start_s = episode_default("settle_s")  # the goal is sent when the settle ends
        return Episode(
            action=HIGH_FIVE_ACTION,
            goal=GO2_ACTIONS[HIGH_FIVE_ACTION].Goal(target_height=height_m, hold_seconds=hold_s),
            plant=self.plant, control_period_s=self.control_period_s, sensors=self.sensors,
            sensor_seed=seed, state=self.state, estimator=self.estimator,
            command_delay_s=self.delay_ticks * self.control_period_s,
            sensor_faults=tuple(replace(f, at_s=f.at_s + start_s) for f in self.sensor_faults),
            pushes=tuple(replace(p, at_s=p.at_s + start_s) for p in pushes),
            controller_params={ControllerConfig.path_of(name): value
                               for name, value in (gains or {}).items()}, **run)


def controller_parts(gains: dict[str, Any] | None, *,
                     control_period_s: float) -> dict[str, dict[str, Any]]:
    """A sweep file's gains (bare names: ``swing_kp``) as :class:`wbc.ControllerConfig`'s
    parts (``{"shaping": {"swing_kp": ...}}``), with the control period: the keyword
    arguments of the controller.

    Raises:
        UnknownNameError: A name that is no parameter (the nearest and the valid ones).
    """
    parts: dict[str, dict[str, Any]] = {"solver": {"control_period_s": control_period_s}}
    for name, value in (gains or {}).items():
        parts.setdefault(ControllerConfig.path_of(name).split(".")[0], {})[name] = value
    return parts


MENAGERIE = Plant.preset("menagerie")
GO2_SENSORS = SensorModel.preset("go2")
#: The default plant, sensors and period: every function's default case.
NOMINAL_CASE = PlantCase()
PLANT_CASES = (
    NOMINAL_CASE,
    PlantCase("foot friction 0.5", MENAGERIE.with_params(foot_friction=0.5)),
    PlantCase("foot friction 0.35", MENAGERIE.with_params(foot_friction=0.35)),
    PlantCase("payload 1.5 kg", MENAGERIE.with_params(payload_kg=1.5)),
    PlantCase("payload 3 kg", MENAGERIE.with_params(payload_kg=3.0)),
    PlantCase("ideal plant", Plant.preset("ideal")),
    PlantCase("unitree-mujoco plant", Plant.preset("unitree-mujoco")),
    PlantCase("identified plant", Plant.preset("identified")),
    PlantCase("delay 1 tick", delay_ticks=1),
    PlantCase("delay 2 ticks", delay_ticks=2),
    PlantCase("delay 4 ticks", delay_ticks=4),
    PlantCase("joint noise 1e-3 rad, 0.05 rad/s", sensors=GO2_SENSORS.with_params(
        joint_position_noise_rad=1e-3, joint_velocity_noise_rad_s=0.05)),
    PlantCase("joint noise 5e-3 rad, 0.1 rad/s", sensors=GO2_SENSORS.with_params(
        joint_position_noise_rad=5e-3, joint_velocity_noise_rad_s=0.1)),
    PlantCase("all: friction 0.5, 1.5 kg, delay 2, noise 1e-3",
              MENAGERIE.with_params(foot_friction=0.5, payload_kg=1.5), delay_ticks=2,
              sensors=GO2_SENSORS.with_params(joint_position_noise_rad=1e-3)),
)
QUICK_PLANT_CASES = (PLANT_CASES[1], PLANT_CASES[9])

#: Payload of the sweeps: 2 kg, 5 cm in front of the base's centre.
SWEEP_PAYLOAD = {"payload_kg": 2.0, "payload_offset_m": (0.05, 0.0, 0.0)}


def _sweep_case(base: Plant, label: str, payload: bool, **joints: float) -> PlantCase:
    changes = {**joints, **(SWEEP_PAYLOAD if payload else {})}
    return PlantCase(f"{label}{', 2 kg' if payload else ''}", base.with_params(**changes))


#: Joint friction the controller does not know, on Menagerie's contacts: damping
#: [N m s/rad] x friction loss [N m] (every joint) x payload.
JOINT_SWEEP = tuple(
    _sweep_case(MENAGERIE, f"damping {d:g}, friction loss {f:g}", p, joint_damping=d,
                joint_friction_loss=f)
    for p in (False, True) for d in (0.0, 0.5, 1.0, 2.0, 3.0) for f in (0.0, 0.2, 0.4))
#: The identified GO2's joints with more calf friction: calf friction loss [N m] x damping
#: [N m s/rad] (every joint) x payload.
CALF_SWEEP = tuple(
    _sweep_case(Plant.preset("identified"), f"calf friction {c:g}, damping {d:g}", p,
                calf_friction_loss=c, joint_damping=d)
    for p in (False, True) for c in (0.2, 0.5, 1.0, 1.4) for d in (0.1, 0.3, 2.0))
QUICK_JOINT_SWEEP = (JOINT_SWEEP[-1],)
QUICK_CALF_SWEEP = (CALF_SWEEP[-1],)
#: The sweeps' high five holds as long as the default episode's (2 s).
SWEEP_HOLD_S: int = episode_default("goal").hold_seconds
#: Plants on which the default controller is compared with one told their joint friction.
COMPENSATION_CASES = (PlantCase("menagerie", MENAGERIE),
                      PlantCase("identified, calf friction 1.4",
                                Plant.preset("identified").with_params(calf_friction_loss=1.4)))
