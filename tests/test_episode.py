"""The episode description: every field checked with a message naming it, defaults in one place."""

from __future__ import annotations

import dataclasses

import pytest

from actions.go2.go2_actions import GO2_ACTIONS
from benchmarks import loop_timing, robustness
from benchmarks.plant_cases import PlantCase
from benchmarks.sweep_spec import SweepSpec
from sim.cli import build_parser
from sim.cli.episode_options import check_options, goal_episode
from sim.disturbances import Push
from sim.episode import GOAL_SLACK_S, Episode, EpisodeError, episode_default
from sim.plant import Plant
from wbc.core.errors import ConfigurationError, UnknownNameError

HighFiveGoal = GO2_ACTIONS["high_five"].Goal
StandGoal = GO2_ACTIONS["stand"].Goal
FollowJointTrajectoryGoal = GO2_ACTIONS["follow_joint_trajectory"].Goal


# ---------------------------------------------------------------------------- checks


@pytest.mark.parametrize(("fields", "field", "message"), [
    ({"state": "exact"}, "state",
     "unknown state source 'exact'; valid state sources: estimate, truth"),
    ({"command_delay_s": 0.0025}, "command_delay_s",
     "expected a whole number of control periods of 0.001 s (e.g. 0.001, 0.009), received 0.0025"),
    ({"command_delay_s": 0.2}, "command_delay_s",
     "expected at most 100 control periods of 0.001 s (0.1 s), received 0.2"),
    ({"control_period_s": 1 / 300}, "control_period_s",
     ("expected a whole number of physics steps of 0.001 s (e.g. 0.001, 0.002, 0.004 s), "
      "received 0.00333333 s")),
    ({"plant": "real"}, "plant",
     ("unknown plant preset 'real'; valid plant presets: menagerie, unitree-mujoco, identified, "
      "ideal")),
    ({"plant_params": {"calf_friction_loss": 9.0}}, "plant_params",
     "calf_friction_loss: expected a value in [0, 5], received 9"),
    ({"sensors": "perfect"}, "sensors",
     "unknown sensor preset 'perfect'; valid sensor presets: go2, exact"),
    ({"sensor_params": {"gyro_noise_rad_s": "high"}}, "sensor_params",
     "gyro_noise_rad_s: expected a number, received 'high'"),
    ({"sensor_seed": -1}, "sensor_seed",
     "expected a whole number in [0, 2147483647], received -1"),
    ({"estimator": "ukf"}, "estimator",
     "unknown state estimator 'ukf'; valid state estimators: inekf, kf"),
    ({"estimator_params": {"trust_timeout_s": -1}}, "estimator_params",
     "trust_timeout_s: expected a value in [0, 10], received -1"),
    ({"controller_params": {"shaping.swing_kp": -1.0}}, "controller_params",
     "shaping.swing_kp: expected a value in [0, 500], received -1"),
    ({"action": "jump"}, "action",
     ("unknown action 'jump'; valid actions: follow_joint_trajectory, high_five, sit, stand, "
      "walk")),
    ({"action": "stand"}, "goal",
     ("expected a StandGoal for the 'stand' action, received HighFiveGoal(target_height=0.4, "
      "hold_seconds=2)")),
    ({"start_pose": "sitting"}, "start_pose",
     "unknown start pose 'sitting'; valid start poses: standing, lying"),
    ({"settle_s": -1.0}, "settle_s", "expected a value in [0, 3600], received -1"),
    ({"pushes": [1]}, "pushes", "expected a sequence of Push instances, received [1]"),
    ({"timeout_s": 0.0}, "timeout_s", "expected a value in (0, inf], received 0"),
    ({"realtime": 1}, "realtime", "expected true or false, received 1"),
])
def test_a_bad_field_is_named_with_what_it_received_and_what_is_valid(fields, field, message):
    with pytest.raises(EpisodeError) as caught:
        Episode(**fields)
    assert caught.value.field == field and caught.value.detail == message
    assert str(caught.value) == f"{field}: {message}"
    assert isinstance(caught.value, ConfigurationError)


def test_an_unknown_field_lists_the_fields():
    with pytest.raises(UnknownNameError) as caught:
        Episode(hieght=0.4)
    fields = ", ".join(f.name for f in dataclasses.fields(Episode))
    assert str(caught.value) == f"unknown episode field 'hieght'; valid episode fields: {fields}"


def test_the_goal_is_a_copy_and_changes_are_checked_again():
    goal = HighFiveGoal(target_height=0.3, hold_seconds=1)
    episode = Episode(goal=goal)
    goal.target_height = 0.45
    assert episode.goal == HighFiveGoal(target_height=0.3, hold_seconds=1)
    with pytest.raises(EpisodeError, match=r"^state: unknown state source 'exact'"):
        episode.replace(state="exact")


def test_resolved_values_follow_the_fields():
    episode = Episode(plant="identified", plant_params={"calf_friction_loss": 1.4},
                      control_period_s=2e-3, command_delay_s=0.004)
    assert episode.plant_model == Plant.preset("identified").with_params(calf_friction_loss=1.4)
    assert episode.plant_params == (("calf_friction_loss", 1.4),)
    assert episode.timestep_s == 1e-3 and episode.control_rate_hz == 500.0
    assert episode.command_delay_ticks == 2
    assert Episode(control_period_s=5e-4).timestep_s == 5e-4  # never longer than the period
    assert Episode().goal_timeout_s == 2 + 8.0 + GOAL_SLACK_S
    assert Episode(timeout_s=5.0).goal_timeout_s == 5.0
    stand = Episode(action="stand", goal=StandGoal(duration_s=1.5))
    assert stand.expected_s == 1.5 and stand.moving_leg == "FR"
    trajectory = FollowJointTrajectoryGoal()
    trajectory.trajectory.joint_names = ["RL_calf_joint"]
    episode = Episode(action="follow_joint_trajectory", goal=trajectory)
    assert episode.moving_leg == "RL" and episode.trajectory_end_s == 0.0


# ---------------------------------------------------------------------------- one place


def test_every_default_is_the_field_default():
    episode = Episode()
    for spec in dataclasses.fields(Episode):
        assert getattr(episode, spec.name) == episode_default(spec.name), spec.name
    assert episode.goal == HighFiveGoal(target_height=0.40, hold_seconds=2)


def test_the_command_lines_defaults_are_the_episodes():
    args = build_parser().parse_args(["high-five"])
    check_options(args)
    goal = HighFiveGoal(target_height=args.height, hold_seconds=args.hold)
    assert goal_episode(args, "high_five", goal) == Episode()
    for command in (["send-goal", "high_five", "{}"], ["stand-pd"]):
        args = build_parser().parse_args(command)
        check_options(args)
        assert args.episode == Episode(action=None)
    for command in ("stand", "sit"):
        assert build_parser().parse_args([command]).duration == StandGoal().duration_s


def test_the_benchmarks_and_sweeps_defaults_are_the_episodes():
    default = Episode()
    assert robustness.SETTLE_S == default.settle_s and robustness.HEIGHT_M == 0.40
    case = PlantCase().episode(height_m=0.40, hold_s=2)
    assert case == dataclasses.replace(default, plant=default.plant_model)
    defaults = loop_timing.episode_defaults()
    assert (defaults["target_height"], defaults["hold_seconds"]) == (0.40, 2)
    assert defaults["control_rate_hz"] == 1000.0 and defaults["settle_s"] == default.settle_s
    resolved = SweepSpec.load("quick").episodes()[0].resolved()
    assert resolved["episode"] == {"settle_s": default.settle_s, "after_s": robustness.AFTER_S,
                                   "timeout_s": robustness.TIMEOUT_S}


def test_push_and_fault_times_of_a_plant_case_count_from_the_goal():
    push = Push(at_s=1.0, force_n=10.0, duration_s=0.1)
    episode = PlantCase().episode(height_m=0.40, hold_s=1, pushes=(push,))
    assert episode.pushes == (dataclasses.replace(push, at_s=1.0 + episode.settle_s),)
