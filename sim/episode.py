"""One simulated episode described in full: :class:`Episode` (the plant, the sensors, the goal...).

An episode is what the command line, the benchmarks and the sweeps run: a fresh MuJoCo GO2
that stands :attr:`Episode.settle_s`, is sent one goal, and runs until its result (then
:attr:`Episode.after_s` more). Every default lives in the fields below; the command line's
options and the benchmarks read them from here (:func:`episode_default`).
:class:`sim.episode_runner.EpisodeRunner` runs one.

Checking an episode imports MuJoCo (the control period is checked against the physics
timestep): a program that chooses MuJoCo's rendering backend does so before it builds one.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, TypeVar

from actions.go2.go2_actions import FOLLOW_JOINT_TRAJECTORY_ACTION, GO2_ACTIONS, HIGH_FIVE_ACTION
from actions.go2.go2_interfaces import HighFiveGoal
from actions.robot.robot_interface import STATE_SOURCES
from actions.ros_interfaces.control_msgs import FollowJointTrajectoryGoal
from sim.disturbances import Push
from sim.plant import DEFAULT_PLANT, Plant
from sim.run_recorder import RAISED_LEG
from sim.sensor_faults import SensorFault
from sim.sensor_model import DEFAULT_SENSORS, SensorModel
from wbc.core.errors import ConfigurationError, WbcError
from wbc.core.validation import as_float, check_name, known_fields_only
from wbc.estimation.estimators import DEFAULT_ESTIMATOR, ESTIMATORS
from wbc.model.description import LEGS

#: The poses an episode may start in.
START_POSES = ("standing", "lying")
#: Sim time [s] a goal may run beyond its expected duration before it is canceled (the
#: default timeout), and the longest wait [s] for the result of a canceled goal.
GOAL_SLACK_S = 30.0
#: The longest command delay, in control periods (:class:`sim.disturbances.DelayedRobot`'s).
MAX_DELAY_TICKS = 100
#: ``(name, value)`` pairs of parameters changed by name, in the order given.
Params = tuple[tuple[str, Any], ...]

_T = TypeVar("_T")


class EpisodeError(ConfigurationError):
    """An episode field with a value that cannot run; :attr:`field` names it.

    Args:
        field: The field (``command_delay_s``).
        detail: What was expected, what was received and what is valid.
    """

    def __init__(self, field: str, detail: str):
        super().__init__(f"{field}: {detail}")
        self.field = field
        self.detail = detail


def _high_five() -> HighFiveGoal:
    return HighFiveGoal(target_height=0.40, hold_seconds=2)


@known_fields_only("episode field")
@dataclass(frozen=True)
class Episode:
    """One goal sent to a fresh simulated GO2, and everything the run depends on.

    Build one with keywords; every field is checked here (:class:`EpisodeError` names the
    field, what it received and what is valid). The defaults are ``go2-wbc high-five``'s.

    Attributes:
        action: The action the goal is sent to (``high_five``, ``stand``, ``sit``,
            ``follow_joint_trajectory``); ``None``: no goal, the robot stands ``after_s``.
        goal: The goal message, of the action's goal type (a validated copy is kept).
        plant: The plant's physics: a preset name (``menagerie``...) or a
            :class:`sim.plant.Plant`.
        plant_params: Plant parameters changed by name (``(("joint_damping", 1.0),)`` or a
            mapping).
        control_period_s: Control period [s] (1e-3: 1 kHz; 2e-3: the GO2's usual 500 Hz).
        physics_timestep_s: Physics timestep [s], a whole number of them per control
            period; ``None``: 1 ms, or the control period if shorter (:attr:`timestep_s`).
        sensors: What the robot measures: a preset name (``go2``, ``exact``) or a
            :class:`sim.sensor_model.SensorModel`.
        sensor_params: Sensor parameters changed by name.
        sensor_seed: Seed of the sensors' noise and biases.
        state: Where the controller's state comes from: ``estimate`` (the estimator on
            the sensors) or ``truth`` (the simulator's exact state).
        estimator: The state estimator (``inekf``, ``kf``), when estimating.
        estimator_params: Estimator parameters changed by name.
        command_delay_s: Time [s] between a command and the motor drivers applying it, a
            whole number of control periods, at most :data:`MAX_DELAY_TICKS` of them.
        sensor_faults: Sensor faults, their times on the simulated clock [s].
        controller_params: Parameters of the default controller by their paths in
            :class:`wbc.ControllerConfig` (``("gains.com_kp", 200.0)``).
        start_pose: The pose the robot starts in (:data:`START_POSES`).
        settle_s: Sim time [s] the robot stands before the goal is sent (the plant spawns
            without contact forces; its feet settle in the first 20 ms).
        calibrate_s: Sim time [s] of a standing calibration after the settle, before the
            goal (0: none): the foot sensors' offset and gain learnt while the centre of
            mass circles, the IMU checked at rest
            (:class:`actions.robot.foot_calibration.StandingCalibration`).
        pushes: Pushes on the robot, their ``at_s`` on the simulated clock [s].
        cancel_at_s: Sim time [s] at which the goal is canceled (``None``: never).
        timeout_s: Sim time [s] after the goal is sent at which it is canceled if it has not
            ended; ``None``: its expected duration + :data:`GOAL_SLACK_S`.
        after_s: Sim time [s] the loop runs on after the result (without a goal: after the
            settle).
        realtime: Pace the simulation to the wall clock.
    """

    action: str | None = HIGH_FIVE_ACTION
    goal: Any = field(default_factory=_high_five)
    plant: str | Plant = DEFAULT_PLANT
    plant_params: Params = ()
    control_period_s: float = 1e-3
    physics_timestep_s: float | None = None
    sensors: str | SensorModel = DEFAULT_SENSORS
    sensor_params: Params = ()
    sensor_seed: int = 0
    state: str = "estimate"
    estimator: str = DEFAULT_ESTIMATOR
    estimator_params: Params = ()
    command_delay_s: float = 0.0
    sensor_faults: tuple[SensorFault, ...] = ()
    controller_params: Params = ()
    start_pose: str = "standing"
    settle_s: float = 0.3
    calibrate_s: float = 0.0
    pushes: tuple[Push, ...] = ()
    cancel_at_s: float | None = None
    timeout_s: float | None = None
    after_s: float = 0.0
    realtime: bool = False

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if self.action is not None:
            _checked("action", lambda: check_name("action", self.action, GO2_ACTIONS))
            goal_type = GO2_ACTIONS[self.action].Goal
            if not isinstance(self.goal, goal_type):
                raise EpisodeError("goal", f"expected a {goal_type.__name__} for the "
                                           f"'{self.action}' action, received {self.goal!r}")
            set_(self, "goal", _checked("goal", self.goal.validated_copy))
        for name in ("plant_params", "sensor_params", "estimator_params", "controller_params"):
            set_(self, name, _params(name, getattr(self, name)))
        self.plant_model  # noqa: B018  (resolved and checked: the preset and its changes)
        self.sensor_model  # noqa: B018
        _checked("control_period_s", lambda: as_float(
            "control_period_s", self.control_period_s, low=0.0, high=0.1, low_inclusive=False))
        if self.physics_timestep_s is not None:
            _checked("physics_timestep_s", lambda: as_float(
                "physics_timestep_s", self.physics_timestep_s, low=1e-5, high=0.01))
        from sim.mujoco_robot import physics_steps_per_period

        _checked("control_period_s",
                 lambda: physics_steps_per_period(self.control_period_s, self.timestep_s))
        _whole("sensor_seed", self.sensor_seed, 2**31 - 1)
        _checked("state", lambda: check_name("state source", self.state, STATE_SOURCES))
        _checked("estimator", lambda: check_name("state estimator", self.estimator, ESTIMATORS))
        if self.estimator_params:
            self.make_estimator()  # its own check of the names and ranges
        self._check_delay()
        set_(self, "sensor_faults", _items("sensor_faults", self.sensor_faults, SensorFault))
        if self.controller_params:
            _checked("controller_params", lambda: self.controller_config)
        _checked("start_pose", lambda: check_name("start pose", self.start_pose, START_POSES))
        _checked("settle_s", lambda: as_float("settle_s", self.settle_s, low=0.0, high=3600.0))
        _checked("calibrate_s", lambda: as_float("calibrate_s", self.calibrate_s, low=0.0,
                                                 high=60.0))
        if self.calibrate_s and self.state != "estimate":
            raise EpisodeError("calibrate_s", f"calibrates the sensors the estimator reads: "
                                              f"expected state 'estimate', received "
                                              f"{self.state!r}")
        if 0.0 < self.calibrate_s < 0.2:
            raise EpisodeError("calibrate_s", f"expected 0 (none) or at least 0.2 s, received "
                                              f"{self.calibrate_s:g}")
        set_(self, "pushes", _items("pushes", self.pushes, Push))
        if self.cancel_at_s is not None:
            _checked("cancel_at_s", lambda: as_float("cancel_at_s", self.cancel_at_s, low=0.0))
        if self.timeout_s is not None:
            _checked("timeout_s", lambda: as_float("timeout_s", self.timeout_s, low=0.0,
                                                   low_inclusive=False))
        _checked("after_s", lambda: as_float("after_s", self.after_s, low=0.0, high=3600.0))
        if not isinstance(self.realtime, bool):
            raise EpisodeError("realtime", f"expected true or false, received {self.realtime!r}")

    def _check_delay(self) -> None:
        delay = _checked("command_delay_s", lambda: as_float(
            "command_delay_s", self.command_delay_s, low=0.0))
        period = self.control_period_s
        ticks = round(delay / period)
        if abs(ticks * period - delay) > 1e-9:
            raise EpisodeError("command_delay_s", (
                f"expected a whole number of control periods of {period:g} s (e.g. "
                f"{period:g}, {9 * period:g}), received {delay:g}"))
        if ticks > MAX_DELAY_TICKS:
            raise EpisodeError("command_delay_s", (
                f"expected at most {MAX_DELAY_TICKS} control periods of {period:g} s "
                f"({MAX_DELAY_TICKS * period:g} s), received {delay:g}"))

    # ------------------------------------------------------------------ resolved values

    @cached_property
    def plant_model(self) -> Plant:
        """The plant: the preset (or the given plant) with :attr:`plant_params` applied."""
        return _resolved(self, "plant", Plant, "plant_params")

    @cached_property
    def sensor_model(self) -> SensorModel:
        """The sensors: the preset (or the given model) with :attr:`sensor_params` applied."""
        return _resolved(self, "sensors", SensorModel, "sensor_params")

    @property
    def timestep_s(self) -> float:
        """The physics timestep [s]: :attr:`physics_timestep_s`, or its default."""
        if self.physics_timestep_s is not None:
            return self.physics_timestep_s
        from sim.control_loop import PHYSICS_TIMESTEP_S

        return min(PHYSICS_TIMESTEP_S, self.control_period_s)

    @property
    def control_rate_hz(self) -> float:
        """The control rate [Hz]."""
        return 1.0 / self.control_period_s

    @property
    def command_delay_ticks(self) -> int:
        """The command delay in control periods."""
        return round(self.command_delay_s / self.control_period_s)

    @property
    def controller_config(self) -> Any:
        """The default controller's :class:`wbc.ControllerConfig`: the episode's control
        period and :attr:`controller_params`."""
        from wbc.controller.controller_config import ControllerConfig

        return ControllerConfig(solver={"control_period_s": self.control_period_s}).with_values(
            dict(self.controller_params))

    def make_estimator(self) -> Any:
        """A new state estimator of :attr:`estimator` with :attr:`estimator_params`."""
        from wbc.estimation.estimators import make_estimator

        return _checked("estimator_params", lambda: make_estimator(
            self.estimator, control_period_s=self.control_period_s,
            **dict(self.estimator_params)))

    @property
    def trajectory_end_s(self) -> float | None:
        """A trajectory goal's last point's time [s] (``None`` for other goals)."""
        if not isinstance(self.goal, FollowJointTrajectoryGoal):
            return None
        points = self.goal.trajectory.points
        return points[-1].time_from_start.to_seconds() if points else 0.0

    @property
    def moving_leg(self) -> str:
        """The leg the goal moves (measured and logged): a trajectory's, or the raised FR."""
        if isinstance(self.goal, FollowJointTrajectoryGoal):
            names = self.goal.trajectory.joint_names
            leg = names[0].split("_")[0] if names else ""
            return leg if leg in LEGS else RAISED_LEG
        return RAISED_LEG

    @property
    def expected_s(self) -> float:
        """How long [s] the goal should take, from its sending to its result."""
        goal = self.goal
        if self.action == FOLLOW_JOINT_TRAJECTORY_ACTION:
            return self.trajectory_end_s + goal.goal_time_tolerance.to_seconds() + 3.0
        if self.action == HIGH_FIVE_ACTION:
            return goal.hold_seconds + 8.0  # shift, unload, raise, lower, reload, shift back
        return float(getattr(goal, "duration_s", 0.0))

    @property
    def goal_timeout_s(self) -> float:
        """:attr:`timeout_s`, or its default: :attr:`expected_s` + :data:`GOAL_SLACK_S`."""
        return self.expected_s + GOAL_SLACK_S if self.timeout_s is None else self.timeout_s

    def replace(self, **changes: Any) -> Episode:
        """This episode with fields changed (checked again)."""
        return dataclasses.replace(self, **changes)


def episode_default(name: str) -> Any:
    """The default of :class:`Episode`'s field ``name`` (a fresh goal message for ``goal``).

    Reading it imports nothing more and checks nothing: the command line reads its option
    defaults this way before it chooses MuJoCo's rendering backend.
    """
    spec = _FIELDS[check_name("episode field", name, _FIELDS)]
    if spec.default is not dataclasses.MISSING:
        return spec.default
    return spec.default_factory()  # type: ignore[misc]


_FIELDS = {f.name: f for f in dataclasses.fields(Episode)}


def _checked(field_name: str, check: Callable[[], _T]) -> _T:
    """``check()``; a library error it raises becomes an :class:`EpisodeError` on the field."""
    try:
        return check()
    except EpisodeError:
        raise
    except WbcError as err:
        detail = str(err)
        raise EpisodeError(field_name, detail.removeprefix(f"{field_name}: ")) from err


def _resolved(episode: Episode, name: str, kind: type[_T], params_name: str) -> _T:
    """Field ``name``: a ``kind`` or a preset's name, with field ``params_name``'s changes."""
    value = getattr(episode, name)
    if isinstance(value, str):
        value = _checked(name, lambda: kind.preset(value))  # type: ignore[attr-defined]
    elif not isinstance(value, kind):
        raise EpisodeError(name, f"expected a preset's name or a {kind.__name__}, received "
                                 f"{value!r}")
    params = dict(getattr(episode, params_name))
    return _checked(params_name, lambda: value.with_params(**params))


def _params(name: str, value: Mapping[str, Any] | Iterable[tuple[str, Any]]) -> Params:
    pairs = value.items() if isinstance(value, Mapping) else value
    try:
        result = tuple((str(key), item) for key, item in pairs)
    except (TypeError, ValueError):
        raise EpisodeError(name, f"expected a mapping of parameter names to values, or "
                                 f"(name, value) pairs, received {value!r}") from None
    return result


def _items(name: str, value: Iterable[Any], kind: type) -> tuple[Any, ...]:
    try:
        items = tuple(value)
    except TypeError:
        items = (value,)
    for item in items:
        if not isinstance(item, kind):
            raise EpisodeError(name, f"expected a sequence of {kind.__name__} instances, "
                                     f"received {value!r}")
    return items


def _whole(name: str, value: Any, high: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= high:
        raise EpisodeError(name, f"expected a whole number in [0, {high}], received {value!r}")
