"""``--set SECTION.FIELD=VALUE``: the short help, the settings reaching the run, the errors,
and the fate of every flag ``--set`` replaced (parsing only: no simulation runs here)."""

from __future__ import annotations

import re

import pytest

from sim.cli import build_parser, main
from sim.cli.episode_options import check_options
from sim.cli.settings import kept_flags

#: What ``go2-wbc high-five --help`` lists: at most 20 options.
HIGH_FIVE_OPTIONS = {
    "--help", "--height", "--hold", "--dds", "--domain", "--interface", "--plant", "--state",
    "--estimator", "--sensors", "--set", "--realtime", "--viewer", "--cancel-at", "--push",
    "--metrics", "--video", "--plot", "--report", "--log"}

#: A value for every flag that still works, hidden from --help, and sets one setting.
KEPT_VALUES = {
    "--control-rate": "500", "--physics-dt": "0.0005", "--command-delay": "0.002",
    "--calibrate": "2", "--sensor-seed": "7", "--sensor-fault": "dropout,3.3,0.02",
    "--start-pose": "lying", "--viewer-exit": None, "--push-at": "2", "--push-dir": "45",
    "--fps": "20", "--video-size": "320x240", "--overlay": "com,target"}


def usage_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1, lines
    return lines[0]


def help_options(command: str, capsys: pytest.CaptureFixture[str]) -> set[str]:
    with pytest.raises(SystemExit):
        main([command, "--help"])
    return set(re.findall(r"^\s+(?:-\w, )?(--[a-z-]+)", capsys.readouterr().out, re.M))


def test_high_five_help_lists_20_options_and_the_goal_commands_fewer(capsys):
    assert help_options("high-five", capsys) == HIGH_FIVE_OPTIONS
    for command in ("stand", "sit", "trajectory", "stand-pd"):
        assert len(help_options(command, capsys)) <= 20, command


@pytest.mark.parametrize("flag", sorted(KEPT_VALUES))
def test_every_kept_flag_sets_what_its_setting_sets(flag):
    assert set(kept_flags()) == set(KEPT_VALUES)  # every kept flag has a case here
    path, value = kept_flags()[flag], KEPT_VALUES[flag]
    parser = build_parser()
    by_flag = parser.parse_args(["high-five", flag] + ([] if value is None else [value]))
    by_set = parser.parse_args(["high-five", "--set", f"{path}={value or 'true'}"])
    default = parser.parse_args(["high-five"])
    changed = [dest for dest in vars(by_set) if dest not in ("settings", "set_by")
               and getattr(by_set, dest) != getattr(default, dest)]
    assert len(changed) == 1, changed
    dest = changed[0]
    assert getattr(by_flag, dest) == getattr(by_set, dest) != getattr(default, dest)
    assert by_set.set_by == {dest: path} and by_flag.set_by == {}


@pytest.mark.parametrize(("command", "flag", "example"), [
    (["high-five"], "--plant-param", "plant.calf_friction_loss=1.4"),
    (["high-five"], "--sensor-param", "sensors.gyro_noise_rad_s=0.01"),
    (["high-five"], "--estimator-param", "estimator.use_foot_force=false"),
    (["stand-pd"], "--plant-param", "plant.calf_friction_loss=1.4"),
    (["bridge"], "--sensor-param", "sensors.gyro_noise_rad_s=0.01"),
    (["run", "--dds"], "--estimator-param", "estimator.use_foot_force=false"),
])
def test_a_removed_flag_names_its_replacement(command, flag, example, capsys):
    line = usage_error([*command, flag, "a=1"], capsys)
    prog = f"go2-wbc {command[0]}"
    section = example.split(".")[0]
    assert line == (f"{prog}: error: {flag} was replaced by --set {section}.<field>=<value> "
                    f"(e.g. --set {example}; --set help lists them) (see '{prog} --help')")


def test_settings_reach_the_episode_and_its_controller():
    args = build_parser().parse_args([
        "high-five", "--set", "controller.gains.com_kp=200", "--set",
        "controller.solver.backend=osqp", "--set",
        "controller.shaping.known_joint_damping=0.1,0.2,0.3",
        "--set", "controller.solver.eliminate_dynamics=false", "--set",
        "estimator.trust_timeout_s=0.05", "--set", "sensors.gyro_noise_rad_s=0.01", "--set",
        "plant.payload_kg=1.5", "--set", "run.control_rate_hz=500", "--set", "sensors.seed=3"])
    check_options(args)
    episode = args.episode
    config = episode.controller_config
    assert (config.gains.com_kp, config.solver.backend) == (200.0, "osqp")
    assert config.shaping.known_joint_damping == (0.1, 0.2, 0.3)
    assert config.solver.eliminate_dynamics is False
    assert config.solver.control_period_s == episode.control_period_s == 0.002
    assert config.gains.foot_kp == 900.0  # the others stay the defaults
    assert dict(episode.estimator_params) == {"trust_timeout_s": 0.05}
    assert episode.make_estimator().config.trust_timeout_s == 0.05
    assert episode.sensor_model.gyro_noise_rad_s == 0.01 and episode.sensor_seed == 3
    assert episode.plant_model.payload_kg == 1.5


@pytest.mark.parametrize(("argv", "message"), [
    (["--set", "controller.com_kp=200"],
     ("--set: unknown setting 'controller.com_kp' in 'controller.com_kp=200' (did you mean "
     "'controller.gains.com_kp'?); valid controller settings: controller.solver.backend, ")),
    (["--set", "sensor.gyro_noise_rad_s=0.01"],
     ("--set: unknown section 'sensor' in 'sensor.gyro_noise_rad_s=0.01' (did you mean "
     "'sensors.gyro_noise_rad_s'?); valid sections: controller, estimator, sensors, plant, "
     "run, push, video (--set help lists every setting)")),
    (["--set", "controller.solver.control_period_s=0.002"],
     ("--set controller.solver.control_period_s: set by the control rate "
     "(--set run.control_rate_hz=HZ)")),
    (["--set", "controller.solver.eliminate_dynamics=maybe"],
     "--set controller.solver.eliminate_dynamics: expected true or false, received 'maybe'"),
    (["--set", "controller.gains.com_kp=-1"],
     "--set controller.gains.com_kp: expected a value in [0, inf], received -1"),
    (["--set", "controller.shaping.swing_kp=high"],
     "--set controller.shaping.swing_kp: expected a number in [0, 500], received 'high'"),
    (["--set", "controller.contacts.max_normal_force_n=5"],  # with the default minimum, 8 N
     ("--set controller.contacts.min_normal_force_n: expected less than max_normal_force_n "
     "(5 N), received 8 N")),
    (["--set", "run.control_rate_hz=0"],
     "--set run.control_rate_hz: expected a rate in [10, 10000] Hz, received 0"),
    (["--set", "run.start_pose=sitting"],
     "--set run.start_pose: expected one of standing, lying, received 'sitting'"),
    (["--set", "push.at_s=2"], "--set push.at_s: only used with --push"),
    (["--set", "video.overlay=com"], "--set video.overlay: only used with --video or --viewer"),
    (["--set", "run.command_delay_s=0.0025"],
     ("--set run.command_delay_s: expected a whole number of control periods of 0.001 s "
      "(e.g. 0.001, 0.009), received 0.0025")),
    (["--set", "sensors.fault=blackout,1,0.1"],
     "--set sensors.fault: unknown sensor fault 'blackout'; valid sensor faults: dropout, "),
    (["--dds", "--set", "sensors.seed=3"],
     ("--set sensors.seed: a simulation option, not used with --dds (the robot on DDS is not "
     "simulated here)")),
])
def test_a_bad_setting_is_one_line_naming_the_path_the_value_and_the_valid_ones(
        argv, message, capsys):
    prog = "go2-wbc high-five"
    line = usage_error(["high-five", *argv], capsys)
    if message.endswith(", "):  # a list of valid names, too long to spell out here
        assert line.startswith(f"{prog}: error: {message}")
        return
    assert line == f"{prog}: error: {message} (see '{prog} --help')"


def test_both_settings_of_a_pair_are_checked_together():
    args = build_parser().parse_args([
        "high-five", "--set", "controller.contacts.max_normal_force_n=5", "--set",
        "controller.contacts.min_normal_force_n=2"])
    check_options(args)  # valid together, in either order
    assert args.episode.controller_config.contacts.max_normal_force_n == 5.0


def test_run_refuses_the_controller_period_and_checks_its_settings(capsys):
    line = usage_error(["run", "--dds", "--set", "controller.solver.control_period_s=0.002"],
                       capsys)
    assert line == ("go2-wbc run: error: --set controller.solver.control_period_s: set by "
                    "--control-rate (see 'go2-wbc run --help')")
    line = usage_error(["run", "--dds", "--set", "controller.gains.com_kp=-1"], capsys)
    assert line == ("go2-wbc run: error: --set controller.gains.com_kp: expected a value in "
                    "[0, inf], received -1 (see 'go2-wbc run --help')")


def test_set_help_lists_every_setting_with_its_default(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", "--set", "help"])
    assert exc.value.code == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "settings (--set SECTION.FIELD=VALUE, repeatable):"
    paths = [line.split()[0] for line in lines[1:]]
    assert "estimator.trust_timeout_s" in paths and "controller.gains.com_kp" in paths
    assert "controller.solver.control_period_s" not in paths  # --control-rate sets it
    assert all("default" in line for line in lines[1:])


@pytest.mark.parametrize(("argv", "message"), [
    (["bridge", "--set", "sensors.gyro_noise_rad_s=high"],
     "--set sensors.gyro_noise_rad_s: expected a number, received 'high'"),
    (["bridge", "--set", "run.control_rate_hz=500"],
     ("--set: unknown section 'run' in 'run.control_rate_hz=500'; valid sections: plant, "
      "sensors (--set help lists every setting)")),
    (["stand-pd", "--set", "sensors.seed=3"],
     ("--set: unknown section 'sensors' in 'sensors.seed=3'; valid sections: plant, run "
      "(--set help lists every setting)")),
])
def test_each_command_takes_the_settings_it_uses(argv, message, capsys):
    prog = f"go2-wbc {argv[0]}"
    assert usage_error(argv, capsys) == f"{prog}: error: {message} (see '{prog} --help')"


def test_send_goal_and_stand_pd_read_their_settings():
    parser = build_parser()
    args = parser.parse_args(["send-goal", "high_five", "{target_height: 0.3}", "--set",
                              "controller.shaping.swing_kp=60", "--set", "sensors.seed=4"])
    check_options(args)
    assert args.episode.controller_config.shaping.swing_kp == 60.0
    assert args.episode.sensor_seed == 4
    args = parser.parse_args(["stand-pd", "--set", "run.control_rate_hz=500", "--set",
                              "plant.joint_damping=1"])
    check_options(args)
    assert args.episode.control_period_s == 0.002
    assert args.episode.plant_model.hip.damping == 1.0
