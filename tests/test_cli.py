"""The go2-wbc command line end to end: output files, exit codes, messages."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import io
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import imageio
import numpy as np
import pytest

from actions.go2.high_five_behaviour import ROBOT_NOT_READY
from actions.go2.robot_context import RobotContext
from sim.cli import (
    EXIT_NOT_SUCCEEDED,
    EXIT_REJECTED,
    EXIT_SUCCEEDED,
    EXIT_UNAVAILABLE,
    EXIT_USAGE,
    SETTLE_S,
    TRAJECTORY_FORMAT_HELP,
    build_parser,
    main,
)
from sim.cli.trajectory_file import load_trajectory_goal
from sim.plant import Plant
from sim.sensor_faults import FAULT_KINDS
from wbc.model.description import JOINT_NAMES, LEGS

HIGH_FIVE_PHASES = ["shifting", "unloading", "raising", "ready", "lowering", "reloading",
                    "shifting_back", "complete"]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: The first line of a run: the state source and the default sensors.
STATE_LINE = (
    "state: estimated (inekf, contact-aided invariant EKF: IMU and leg kinematics) from "
    "sensors go2 (gyro 0.004 rad/s, accel 0.03 m/s^2, attitude filter 5 s; joints 5e-05 rad / "
    "0.02 rad/s; feet 2.5 counts/N), seed 0")
#: The second line of a run on the default plant and rates.
MENAGERIE_LINE = (
    "plant menagerie (joints: damping 2 N m s/rad, friction loss 0.2 N m, armature 0.01 "
    "kg m^2; feet: friction 0.8, condim 6, elliptic cones, impratio 100); control 1000 Hz, "
    "physics 1 ms")
#: The third line of a run on the estimate: the foot sensors' calibration in use.
FEET_LINE = ("feet: foot force [counts] = offset + gain x N (default): FL 10 + 2.5/N, "
             "FR 10 + 2.5/N, RL 10 + 2.5/N, RR 10 + 2.5/N")
WAVE_YAML = """\
joint_names: [FR_hip_joint, FR_thigh_joint, FR_calf_joint]
points:
  - positions: [-0.1, -0.3, -1.6]
    velocities: [0.0, -0.5, 0.8]
    time_from_start: 1.0
  - positions: [-0.1, -0.5, -1.2]
    velocities: [0.0, 0.0, 0.0]
    time_from_start: 1.5
goal_tolerance:
  - {name: FR_thigh_joint, position: 0.05}
goal_time_tolerance: 0.5
"""


def run(argv: list[str]) -> tuple[int, str]:
    """``main(argv)`` in this process; returns the exit code and what it printed."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    return code, out.getvalue()


def usage_error(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    """Parse ``argv``, expecting exit 2; returns the message (checked to be one line)."""
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    return lines[0]


def offscreen_rendering_works() -> bool:
    """Whether a fresh process that chooses its GL backend first can render a frame."""
    probe = ("from sim.video_recorder import choose_offscreen_gl; choose_offscreen_gl(); "
             "import mujoco; model = mujoco.MjModel.from_xml_string('<mujoco/>'); "
             "mujoco.Renderer(model, 16, 16).render()")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, timeout=60,
                          check=False)
    return done.returncode == 0


@pytest.fixture(scope="module")
def high_five(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """One high five with a 0 s hold and every file output except the video."""
    folder = tmp_path_factory.mktemp("high_five")
    paths = {"report": folder / "run.json", "log": folder / "run.npz",
             "plot": folder / "run.png"}
    code, out = run(["high-five", "--hold", "0", "--report", str(paths["report"]),
                     "--log", str(paths["log"]), "--plot", str(paths["plot"])])
    return {"code": code, "out": out, "paths": paths,
            "report": json.loads(paths["report"].read_text())}


# ----------------------------------------------------------------------------- a high five


def test_high_five_succeeds_and_prints_each_phase_once_then_the_result(high_five):
    assert high_five["code"] == EXIT_SUCCEEDED
    lines = high_five["out"].splitlines()
    assert lines.pop(0) == STATE_LINE
    assert lines.pop(0) == MENAGERIE_LINE
    assert lines.pop(0) == FEET_LINE
    assert lines[0] == (f"[{SETTLE_S:7.3f} s] high_five: sending goal "
                        "(target_height 0.40 m, hold 0 s)")
    assert lines[1] == f"[{SETTLE_S:7.3f} s] goal accepted"
    # Not a terminal: one plain line per phase, no progress line.
    phase_lines = lines[2:2 + len(HIGH_FIVE_PHASES)]
    assert [line.split()[-1] for line in phase_lines] == HIGH_FIVE_PHASES
    assert "\r" not in high_five["out"]
    assert lines[10].endswith("result: SUCCEEDED: high five done: foot raised to 0.400 m, "
                              "held 0 s, back on four feet")
    assert lines[11].startswith("metrics: raised foot error RMS ")
    assert re.fullmatch(r"estimate vs truth: base velocity error RMS \d\.\d mm/s \(max "
                        r"\d+\.\d\); height error max \d\.\d\d mm; roll / pitch error max "
                        r"0\.\d\d / 0\.\d\d deg; drift \d\.\d mm horizontal, -?0\.\d\d deg "
                        r"yaw", lines[12]), lines[12]
    assert lines[13:] == [f"wrote {high_five['paths'][k]}" + suffix for k, suffix in
                          (("report", ""), ("log", " (5806 ticks)"), ("plot", ""))]


def test_report_has_the_result_phases_in_order_and_the_feedback(high_five):
    report = high_five["report"]
    assert report["action"] == "high_five"
    assert report["goal"] == {"target_height": 0.4, "hold_seconds": 0}
    plant = json.loads(json.dumps(dataclasses.asdict(Plant.preset("menagerie"))))
    assert report["plant"] == plant and report["plant"]["name"] == "menagerie"
    assert report["control_rate_hz"] == 1000.0 and report["physics_timestep_s"] == 0.001
    state = report["state"]
    assert state["source"] == "estimate" and state["sensors"]["name"] == "go2"
    assert state["sensors"]["gyro_noise_rad_s"] == 0.004 and state["sensor_seed"] == 0
    assert state["estimator"] == "inekf"
    assert state["estimator_config"]["trust_timeout_s"] == 0.01
    assert state["command_delay_s"] == 0.0
    assert state["sensor_faults"] == []
    assert report["result"] == {
        "status": "SUCCEEDED", "success": True,
        "message": "high five done: foot raised to 0.400 m, held 0 s, back on four feet"}
    phases = report["phases"]
    assert [p["phase"] for p in phases] == HIGH_FIVE_PHASES
    times = [p["t_s"] for p in phases]
    assert times[0] == pytest.approx(SETTLE_S) and times == sorted(times)
    # Shift 1.0 s, unload 0.4 s, raise 1.5 s, (hold 0 s), lower 1.5 s, reload 0.4 s, shift 1.0 s.
    assert np.diff(times) == pytest.approx([1.0, 0.4, 1.5, 0.0, 1.5, 0.4, 1.0], abs=0.005)
    feedback = report["feedback"]
    progress = [f["progress"] for f in feedback]
    assert progress == sorted(progress) and progress[-1] == 1.0
    assert max(np.diff([f["t_s"] for f in feedback])) <= 0.02 + 1e-6  # 50 Hz at least
    assert [e["event"] for e in report["events"]] == ["accepted", "result"]


def test_report_metrics_meet_the_controller_goals(high_five):
    m = high_five["report"]["metrics"]
    assert set(m) >= {
        "raised_foot_rms_mm", "raised_foot_max_mm", "holding_rms_mm", "stance_sliding_max_mm",
        "stance_travel_max_mm", "min_stance_normal_force_n", "min_com_margin_mm",
        "max_base_tilt_deg", "max_torque_fraction", "qp_failures", "tick_median_us",
        "tick_p99_us", "tick_max_us", "real_time_factor"}
    assert m["ticks"] == 5806 and m["duration_s"] == pytest.approx(5.806)
    assert m["raised_foot_rms_mm"] <= 5.0 and m["raised_foot_max_mm"] <= 10.0
    assert m["stance_sliding_max_mm"] <= 2.0  # measured from the goal, after the settle
    assert m["stance_travel_max_mm"] <= 10.0  # the spheres roll; the lift tests bound it tightly
    assert m["min_stance_normal_force_n"] >= 5.0
    assert m["min_com_margin_mm"] > 10.0
    assert m["max_base_tilt_deg"] < 3.0 and not m["fell"]
    assert m["max_torque_fraction"] <= 0.9
    assert m["qp_failures"] == 0
    assert 0 < m["estimate_velocity_rms_m_s"] <= 0.02 and 0 < m["estimate_height_max_mm"] <= 3.0
    assert m["estimate_roll_max_deg"] <= 0.3 and m["estimate_pitch_max_deg"] <= 0.3
    assert 0 < m["tick_median_us"] <= m["tick_p99_us"] <= m["tick_max_us"]
    assert m["real_time_factor"] > 0


def test_log_has_one_row_per_tick_with_consistent_arrays(high_five):
    log = np.load(high_five["paths"]["log"])
    n = 5806
    shapes = {"t_s": (n,), "q": (n, 19), "v": (n, 18), "q_true": (n, 19), "v_true": (n, 18),
              "estimate_contact": (n, 4), "estimate_flags": (n,), "tau": (n, 12),
              "foot_target": (n, 3), "foot_position": (n, 3), "phase": (n,),
              "contact_forces": (n, 4, 3), "com_margin_m": (n,), "qp_ok": (n,),
              "tick_us": (n,)}
    assert {k: log[k].shape for k in shapes} == shapes
    assert list(log["joint_names"]) == list(JOINT_NAMES)
    assert list(log["legs"]) == list(LEGS) and str(log["raised_leg"]) == "FR"
    assert np.allclose(np.diff(log["t_s"]), 1e-3) and log["t_s"][0] == pytest.approx(SETTLE_S)
    assert np.allclose(np.linalg.norm(log["q"][:, 3:7], axis=1), 1.0)
    # The controller's state is the estimate, beside the truth at the same instants.
    assert np.abs(log["q"][:, 2] - log["q_true"][:, 2]).max() <= 3e-3
    assert np.abs(log["v"][:, :3] - log["v_true"][:, :3]).max() <= 0.03
    assert not np.array_equal(log["q"], log["q_true"])
    assert not log["estimate_flags"].any()
    fr = LEGS.index("FR")  # in the air while holding: no weight in the filter
    assert np.all(log["estimate_contact"][log["phase"] == "ready", fr] == 0.0)
    phases = list(dict.fromkeys(log["phase"]))
    assert phases == HIGH_FIVE_PHASES
    tracking = np.isin(log["phase"], ["raising", "ready", "lowering"])
    assert np.all(np.isfinite(log["foot_target"][tracking]))
    assert np.all(np.isnan(log["foot_target"][~tracking]))
    assert np.nanmax(log["foot_target"][:, 2]) == pytest.approx(0.40, abs=1e-6)
    foot_error = np.linalg.norm(log["foot_position"] - log["foot_target"], axis=1)[tracking]
    assert foot_error.max() <= 0.010
    fr_normal = log["contact_forces"][:, LEGS.index("FR"), 2]
    assert np.all(fr_normal[log["phase"] == "ready"] == 0.0)  # in the air, per MuJoCo
    total = log["contact_forces"][:, :, 2].sum(axis=1)
    assert np.median(total) == pytest.approx(15.0 * 9.81, rel=0.1)  # carries its weight
    assert log["qp_ok"].all()


def test_plot_is_a_png(high_five):
    data = high_five["paths"]["plot"].read_bytes()
    assert data.startswith(PNG_SIGNATURE) and len(data) > 20_000


def test_cancel_at_ends_canceled_with_the_foot_down(tmp_path):
    report_path = tmp_path / "cancel.json"
    code, out = run(["high-five", "--cancel-at", "2.5", "--report", str(report_path)])
    assert code == EXIT_NOT_SUCCEEDED
    report = json.loads(report_path.read_text())
    assert report["result"]["status"] == "CANCELED" and not report["result"]["success"]
    assert "the foot is down" in report["result"]["message"]
    cancel = [e for e in report["events"] if e["event"] == "cancel_requested"]
    assert cancel == [{"t_s": 2.5, "event": "cancel_requested", "reason": "--cancel-at 2.5"}]
    phases = [p["phase"] for p in report["phases"]]
    assert phases[:3] == ["shifting", "unloading", "raising"] and phases[-1] == "canceled"
    assert "cancel accepted" in out
    assert report["metrics"]["qp_failures"] == 0


def test_push_goes_in_the_requested_direction_relative_to_the_heading(tmp_path):
    report_path, log_path = tmp_path / "push.json", tmp_path / "push.npz"
    code, _ = run(["stand", "--start-pose", "standing", "--duration", "0.5",
                   "--push", "60,0.1", "--push-at", "0.35", "--push-dir", "90",
                   "--report", str(report_path), "--log", str(log_path)])
    assert code == EXIT_SUCCEEDED
    (push,) = [e for e in json.loads(report_path.read_text())["events"] if e["event"] == "push"]
    assert push["t_s"] == pytest.approx(0.35)
    assert push["force_n"] == pytest.approx([0.0, 60.0, 0.0], abs=0.5)  # 90 deg: to the left
    log = np.load(log_path)
    after = log["t_s"] > 0.45
    base_y = log["q"][:, 1]
    assert base_y[after].max() - base_y[0] > 0.001  # moved left


def test_sit_and_stand_succeed(tmp_path):
    code, out = run(["sit", "--duration", "0.5"])
    assert code == EXIT_SUCCEEDED and "result: SUCCEEDED: reached the lying pose" in out
    code, out = run(["stand", "--duration", "0.5"])  # from lying, the default start pose
    assert code == EXIT_SUCCEEDED and "result: SUCCEEDED: reached the standing pose" in out


# ----------------------------------------------------------------------------- rejections


def test_a_rejected_goal_exits_3_and_prints_the_reason(monkeypatch, tmp_path):
    monkeypatch.setattr(RobotContext, "is_upright", lambda self: False)
    report_path = tmp_path / "rejected.json"
    code, out = run(["high-five", "--report", str(report_path)])
    assert code == EXIT_REJECTED
    assert f"goal rejected (code {ROBOT_NOT_READY}): robot not able: base tilt" in out
    result = json.loads(report_path.read_text())["result"]
    assert result["status"] == "REJECTED" and result["rejection_code"] == ROBOT_NOT_READY


def test_a_trajectory_with_an_unknown_joint_is_rejected_by_the_server(tmp_path):
    path = tmp_path / "bad_joint.yaml"
    path.write_text(WAVE_YAML.replace("FR_hip_joint", "FR_elbow_joint"))
    code, out = run(["trajectory", str(path)])
    assert code == EXIT_REJECTED
    assert ("goal rejected (code -2): trajectory.joint_names[0]: unknown joint "
            "'FR_elbow_joint'; valid joints: FL_hip_joint") in out


# ----------------------------------------------------------------------------- trajectories


def test_trajectory_file_yaml_and_json_give_the_same_goal(tmp_path):
    import yaml

    yaml_path, json_path = tmp_path / "wave.yaml", tmp_path / "wave.json"
    yaml_path.write_text(WAVE_YAML)
    json_path.write_text(json.dumps(yaml.safe_load(WAVE_YAML)))
    goal = load_trajectory_goal(yaml_path)
    assert goal == load_trajectory_goal(json_path)
    assert goal.trajectory.joint_names == ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"]
    assert [p.time_from_start.to_seconds() for p in goal.trajectory.points] == [1.0, 1.5]
    assert goal.trajectory.points[0].velocities == [0.0, -0.5, 0.8]
    assert goal.trajectory.points[1].accelerations == []
    assert [(t.name, t.position) for t in goal.goal_tolerance] == [("FR_thigh_joint", 0.05)]
    assert goal.path_tolerance == [] and goal.goal_time_tolerance.to_seconds() == 0.5


def test_the_format_shown_by_help_is_a_valid_trajectory_file(tmp_path):
    path = tmp_path / "from_help.yaml"
    path.write_text(TRAJECTORY_FORMAT_HELP.split("\n", 1)[1].split("\nA file")[0])
    goal = load_trajectory_goal(path)
    assert goal.trajectory.joint_names == ["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"]
    (point,) = goal.trajectory.points
    assert point.positions == [-0.1, -0.3, -1.6] and point.time_from_start.to_seconds() == 2.0
    assert [t.name for t in goal.path_tolerance + goal.goal_tolerance] == ["FR_thigh_joint"] * 2
    assert goal.goal_time_tolerance.to_seconds() == 0.5


def test_trajectory_from_a_file_succeeds(tmp_path):
    path = tmp_path / "wave.yaml"
    path.write_text(WAVE_YAML)
    code, out = run(["trajectory", str(path)])
    assert code == EXIT_SUCCEEDED, out
    # FollowJointTrajectory feedback has no phase: the phase shown follows the trajectory
    # time reached (0 while the leg is released, then up to the last point's 1.5 s, then past).
    shown = re.findall(r"^\[ *([\d.]+) s\] +(\d+) %  (\S+)", out, re.MULTILINE)
    assert [phase for _, _, phase in shown] == ["starting", "following", "settling"]
    (start_s, start_pct, _), (follow_s, _, _), (_, end_pct, _) = shown
    assert float(start_s) == pytest.approx(0.3, abs=2e-3) and start_pct == "0"
    assert 1.7 < float(follow_s) < 1.75  # the release takes 1.4 s
    assert end_pct == "100"
    assert out.splitlines()[-1].endswith(
        "result: SUCCEEDED (error_code 0): goal reached: the FR leg holds the last point, in "
        "swing: the FR foot stays up and the robot stands on three feet; a Stand goal puts the "
        "foot down")


# ----------------------------------------------------------------------------- bad arguments


@pytest.mark.parametrize(("argv", "message"), [
    (["jump"], ("COMMAND: invalid choice: 'jump' (choose from 'high-five', 'stand', 'sit', "
                "'trajectory', 'walk', 'stand-pd', 'send-goal', 'actions', 'interface', 'bridge', "
                "'run', 'check', 'replay', 'ros2', 'teleop')")),
    ([], "the following arguments are required: COMMAND"),
    (["high-five", "--height", "0.9"],
     "--height: expected a height in [0.10, 0.50] m, received 0.9"),
    (["walk", "--forward", "1.5"],
     "--forward: expected a forward velocity in [-1, 1] m/s, received 1.5"),
    (["walk", "--yaw-rate", "fast"],
     ("--yaw-rate: expected a turning rate (counter-clockwise) in [-1.2, 1.2] rad/s, "
      "received 'fast'")),
    (["walk", "--duration", "3", "--distance", "2"],
     "--distance: not allowed with argument --duration"),
    (["high-five", "--height", "high"],
     "--height: expected a height in [0.10, 0.50] m, received 'high'"),
    (["high-five", "--hold", "1.5"],
     "--hold: expected a whole number of seconds in [0, 60], received '1.5'"),
    (["sit", "--duration", "0.1"], "--duration: expected a duration in [0.5, 10] s, received 0.1"),
    (["high-five", "--push", "40"], ("--push: expected FORCE_N,DURATION_S with a force in "
                                     "[0, 500] N and a duration in (0, 5] s (e.g. 40,0.1), "
                                     "received '40'")),
    (["high-five", "--push-at", "2"], "--push-at: only used with --push"),
    (["high-five", "--video", "run.avi"],
     "--video: expected a file name ending in .mp4, received 'run.avi'"),
    (["high-five", "--video", "v.mp4", "--video-size", "640x"],
     ("--video-size: expected WIDTHxHEIGHT in pixels, both even and in [16, 3840] "
      "(e.g. 640x480), received '640x'")),
    (["high-five", "--video", "v.mp4", "--overlay", "com,bogus"],
     ("--overlay: expected a comma-separated list of com, polygon, forces, measured, target, "
      "gait, or all or none; received 'com,bogus'")),
    (["high-five", "--overlay", "com"], "--overlay: only used with --video or --viewer"),
    (["high-five", "--viewer-exit"], "--viewer-exit: only used with --viewer"),
    (["high-five", "--report", "/no/such/dir/r.json"],
     "--report: directory '/no/such/dir' does not exist (for '/no/such/dir/r.json')"),
    (["trajectory", "/no/such/file.yaml"],
     "FILE: cannot read '/no/such/file.yaml': No such file or directory"),
])
def test_bad_arguments_exit_2_with_one_line_naming_the_option(argv, message, capsys):
    line = usage_error(argv, capsys)
    prog = " ".join(["go2-wbc", *argv[:1]]) if argv and argv[0] != "jump" else "go2-wbc"
    assert line == f"{prog}: error: {message} (see '{prog} --help')"


@pytest.mark.parametrize(("content", "message"), [
    ("joint_names: [FR_hip_joint]\npoints:\n  - positions: [0.1]\n    time: 1\n",
     ("points[0]: unknown key 'time'; valid keys: positions, velocities, accelerations, "
      "effort, time_from_start")),
    ("joint_names: [FR_hip_joint]\npoints:\n  - positions: [x]\n    time_from_start: 1\n",
     ("points[0]: JointTrajectoryPoint.positions[0] must be a real number; received 'x' "
      "(type str)")),
    ("joint_names: [FR_hip_joint\n",
     "YAML error at line 2, column 1: expected ',' or ']', but got '<stream end>'"),
    ("- 1\n", ("file: expected a mapping with keys joint_names, points, path_tolerance, "
               "goal_tolerance, goal_time_tolerance, received list")),
    ("joint_names: [FR_hip_joint]\n", "file: missing key 'points'"),
])
def test_an_invalid_trajectory_file_exits_2_and_says_what_is_wrong(content, message, tmp_path,
                                                                   capsys):
    path = tmp_path / "bad.yaml"
    path.write_text(content)
    line = usage_error(["trajectory", str(path)], capsys)
    assert line == (f"go2-wbc trajectory: error: FILE: '{path}' is not a valid trajectory "
                    f"file: {message} (see 'go2-wbc trajectory --help')")


def test_every_option_says_its_default(capsys):
    parser = build_parser()
    with pytest.raises(SystemExit) as exc:
        main(["high-five", "--help"])
    assert exc.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    with pytest.raises(SystemExit) as exc:
        main(["high-five", "--set", "help"])
    assert exc.value.code == 0
    text += " " + " ".join(capsys.readouterr().out.split())
    for phrase in ("--height M foot height above the ground [m], in [0.10, 0.50] (default: 0.40)",
                   ("--hold S seconds to hold the foot up [s], a whole number in [0, 60] "
                    "(default: 2)"),
                   "video.fps video frame rate [1/s] of simulated time (default: 30)",
                   "video.size video frame size in pixels, WxH (default: 640x480)",
                   "3 the action server rejected the goal"):
        assert phrase in text
    subparsers = parser._subparsers._group_actions[0].choices  # argparse keeps them here
    for name, sub in subparsers.items():
        for action in sub._actions:
            if action.help == argparse.SUPPRESS:  # a kept or removed flag: --set says it
                continue
            if action.option_strings and action.dest != "help":
                assert "default" in action.help, (name, action.option_strings)
            if action.dest == "settings":  # every setting, too
                for setting in action.settings.values():
                    assert "default" in setting.help, (name, setting.path)


# ------------------------------------------------------------------------ the installed command


def test_installed_command_records_a_video_of_the_right_size(tmp_path):
    command = Path(sys.executable).with_name("go2-wbc")
    argv = [str(command)] if command.exists() else [sys.executable, "-m", "sim.cli"]
    video, report = tmp_path / "sit.mp4", tmp_path / "sit.json"
    done = subprocess.run(
        [*argv, "sit", "--duration", "1", "--video", str(video), "--fps", "10",
         "--video-size", "160x120", "--report", str(report)],
        capture_output=True, text=True, timeout=120, check=False)
    if done.returncode == 4 and "offscreen rendering is unavailable" in done.stderr:
        # Skip only if a fresh process cannot render either: the CLI must choose MUJOCO_GL
        # before anything imports MuJoCo, or it renders nowhere.
        assert not offscreen_rendering_works(), done.stderr
        pytest.skip(f"no offscreen OpenGL on this machine: {done.stderr.strip()}")
    assert done.returncode == EXIT_SUCCEEDED, done.stdout + done.stderr
    assert json.loads(report.read_text())["result"]["success"] is True
    with imageio.get_reader(video) as reader:
        frames = list(reader.iter_data())  # the reader's len() is inf
    assert len(frames) == 1 + math.floor(1.0 * 10 + 1e-9)  # t = 0.3, 0.4, ..., 1.3 s
    assert all(f.shape == (120, 160, 3) for f in frames)
    # The robot lies down: the last frame differs from the first.
    assert np.abs(frames[-1].astype(float) - frames[0].astype(float)).mean() > 1.0
    # The overlays are on by default: the support polygon's green is on the floor.
    red, green, blue = (frames[0][..., k].astype(int) for k in range(3))
    assert ((green > red + 60) & (green > blue + 60)).sum() > 20
    assert f"wrote {video} ({len(frames)} frames at 10 fps)" in done.stdout


# ---------------------------------------------------------------------------- the plant
# The default plant's line and report: test_high_five_succeeds... and test_report_has...


def test_stand_pd_runs_the_ideal_plant_at_the_control_rate():
    code, out = run(["stand-pd", "--plant", "ideal", "--control-rate", "500", "--duration",
                     "0.1"])
    assert code == EXIT_SUCCEEDED
    lines = out.splitlines()
    assert lines[0] == (
        "plant ideal (joints: damping 0 N m s/rad, friction loss 0 N m, armature 0 kg m^2; "
        "feet: friction 1, condim 3, elliptic cones, impratio 10); control 500 Hz, physics "
        "1 ms")
    assert lines[1] == "stood 0.10 s under a joint PD with gravity compensation"


def test_plant_parameters_and_500_hz_reach_the_run_and_the_report(tmp_path):
    report = tmp_path / "r.json"
    code, out = run(["high-five", "--height", "0.25", "--hold", "0", "--plant", "identified",
                     "--set", "plant.calf_friction_loss=1.4", "--set",
                     "plant.payload_offset_m=0.05,0,0", "--set", "run.control_rate_hz=500",
                     "--report", str(report)])
    assert code == EXIT_SUCCEEDED, out
    first = out.splitlines()[1]
    assert first.startswith("plant identified + calf_friction_loss=1.4, "
                            "payload_offset_m=(0.05, 0, 0) (hip: damping 0.2")
    assert "calf: damping 0.2 N m s/rad, friction loss 1.4 N m" in first
    assert first.endswith("control 500 Hz, physics 1 ms")
    data = json.loads(report.read_text())
    assert data["plant"]["name"].startswith("identified + calf_friction_loss=1.4")
    assert data["plant"]["calf"]["friction_loss"] == 1.4
    assert data["plant"]["hip"]["friction_loss"] == 0.25  # the preset's, unchanged
    assert data["plant"]["payload_offset_m"] == [0.05, 0.0, 0.0]
    assert data["control_rate_hz"] == 500.0 and data["physics_timestep_s"] == 0.001
    metrics = data["metrics"]  # the loop ticked at 500 Hz of sim time
    assert metrics["ticks"] == pytest.approx(500 * metrics["duration_s"], abs=1)
    assert data["result"]["success"] and metrics["qp_failures"] == 0


@pytest.mark.parametrize(("argv", "message"), [
    (["--plant", "real"], ("--plant: invalid choice: 'real' (choose from 'menagerie', "
                           "'unitree-mujoco', 'identified', 'ideal')")),
    (["--set", "plant.knee_damping=1"],
     ("--set: unknown setting 'plant.knee_damping' in 'plant.knee_damping=1' (did you mean "
      "'plant.joint_damping'?); valid plant settings: "
      + ", ".join(f"plant.{name}" for name in Plant.parameter_names()))),
    (["--set", "plant.joint_damping=-1"],
     "--set plant.joint_damping: expected a value in [0, 10], received -1"),
    (["--set", "plant.calf_friction_loss=9"],
     "--set plant.calf_friction_loss: expected a value in [0, 5], received 9"),
    (["--set", "plant.payload_offset_m=0.1,0"],
     ("--set plant.payload_offset_m: expected three numbers (x, y, z) [m], received "
      "(0.1, 0.0)")),
    (["--set", "plant.cone=round"],
     "--set plant.cone: unknown cone 'round'; valid cones: elliptic, pyramidal"),
    (["--set", "foo"], ("--set: expected SECTION.FIELD=VALUE (e.g. "
                        "estimator.trust_timeout_s=0.05), received 'foo'")),
    (["--control-rate", "300", "--physics-dt", "0.001"],
     ("--control-rate: 300 Hz with --physics-dt 0.001 s: control_period_s: expected a whole "
      "number of physics steps of 0.001 s (e.g. 0.001, 0.002, 0.004 s), received "
      "0.00333333 s")),
    (["--control-rate", "300"],  # the default timestep, 1 ms, does not divide it either
     ("--control-rate: 300 Hz with --physics-dt 0.001 s: control_period_s: expected a whole "
      "number of physics steps of 0.001 s (e.g. 0.001, 0.002, 0.004 s), received "
      "0.00333333 s")),
    (["--control-rate", "0"], "--control-rate: expected a rate in [10, 10000] Hz, received 0"),
    (["--state", "exact"], "--state: invalid choice: 'exact' (choose from 'estimate', 'truth')"),
    (["--sensors", "perfect"], ("--sensors: invalid choice: 'perfect' (choose from 'go2', "
                                "'exact')")),
    (["--set", "sensors.gyro=1"],
     ("--set: unknown setting 'sensors.gyro' in 'sensors.gyro=1' (did you mean "
      "'sensors.gyro_bias_walk'?); valid sensors settings: "
      "sensors.gyro_noise_rad_s, sensors.gyro_bias_rad_s, sensors.gyro_bias_walk, "
      "sensors.accel_noise_m_s2, sensors.accel_bias_m_s2, sensors.accel_bias_walk, "
      "sensors.attitude_time_constant_s, sensors.joint_position_noise_rad, "
      "sensors.joint_position_resolution_rad, sensors.joint_velocity_noise_rad_s, "
      "sensors.joint_torque_noise_nm, sensors.foot_force_offset, sensors.foot_force_gain, "
      "sensors.foot_force_noise, sensors.foot_force_full_scale, sensors.foot_force_integer, "
      "sensors.seed, sensors.fault")),
    (["--set", "sensors.gyro_noise_rad_s=nan"],
     "--set sensors.gyro_noise_rad_s: expected a finite number, received nan"),
    (["--set", "sensors.gyro_noise_rad_s=high"],
     "--set sensors.gyro_noise_rad_s: expected a number, received 'high'"),
    (["--sensor-fault", "blackout,1,0.1"],
     ("--sensor-fault: unknown sensor fault 'blackout'; valid sensor faults: "
      + ", ".join(FAULT_KINDS))),
    (["--sensor-fault", "dropout,1"],
     ("--sensor-fault: expected KIND,AT_S,DURATION_S[,FOOT_OR_JOINT] with KIND one of "
      + ", ".join(FAULT_KINDS) + " (e.g. dropout,3.5,0.02 or foot_zero,1,5,RL), received "
      "'dropout,1'")),
    (["--sensor-fault", "foot_zero,1,0.1,XL"],
     "--sensor-fault: unknown leg 'XL'; valid legs: FL, FR, RL, RR"),
    (["--estimator", "ukf"], "--estimator: invalid choice: 'ukf' (choose from 'inekf', 'kf')"),
    (["--set", "estimator.trust=1"],
     ("--set: unknown setting 'estimator.trust' in 'estimator.trust=1' (did you mean "
      "'estimator.trust_timeout_s'?); valid estimator settings: "
      "estimator.quaternion_tolerance, ")),
    (["--set", "estimator.trust_timeout_s=-1"],
     "--set estimator.trust_timeout_s: expected a value in [0, 10], received -1"),
    (["--command-delay", "0.0025"],
     ("--command-delay: expected a whole number of control periods of 0.001 s (e.g. 0.001, "
      "0.009), received 0.0025")),
])
def test_bad_plant_and_rate_options_are_one_line_usage_errors(argv, message, capsys):
    prog = "go2-wbc high-five"
    line = usage_error(["high-five", *argv], capsys)
    if message.endswith(", "):  # a list of valid names, too long to spell out here
        assert line.startswith(f"{prog}: error: {message}")
        return
    assert line == f"{prog}: error: {message} (see '{prog} --help')"


def test_truth_state_exact_sensors_and_a_fault_reach_the_run(tmp_path):
    code, out = run(["high-five", "--hold", "0", "--state", "truth", "--sensors", "exact",
                     "--metrics"])
    assert code == EXIT_SUCCEEDED, out
    lines = out.splitlines()
    assert lines[0] == ("state: the simulator's exact state (--state truth; a GO2 measures no "
                        "base position or velocity); sensors exact (the true state, no noise) "
                        "unused")
    assert "estimate vs truth" not in out
    report = tmp_path / "fault.json"
    code, out = run(["high-five", "--hold", "1", "--sensor-fault", "dropout,3.3,0.02",
                     "--set", "sensors.gyro_noise_rad_s=0.01", "--command-delay", "0.002",
                     "--estimator", "kf", "--set", "estimator.use_foot_force=false",
                     "--report", str(report)])
    assert code == EXIT_NOT_SUCCEEDED, out
    lines = out.splitlines()
    assert lines[0].startswith("state: estimated (kf, linear Kalman filter: the IMU's "
                               "orientation and leg kinematics, use_foot_force=False) from ")
    assert lines[0].endswith("seed 0; fault: no sample arrives from 3.3 s for 20 ms")
    assert "gyro 0.01 rad/s" in lines[0]
    assert lines[1].endswith("; commands applied 2 ms late")
    assert ("result: ABORTED: the state stopped being trustworthy (state estimate: no "
            "trustworthy sensor sample for 11 ms (limit 10 ms): no sensor sample this period) "
            "while the goal was EXECUTING") in out
    state = json.loads(report.read_text())["state"]
    assert state["sensor_faults"] == [{"kind": "dropout", "at_s": 3.3, "duration_s": 0.02,
                                       "name": ""}]
    assert state["command_delay_s"] == 0.002 and state["sensors"]["gyro_noise_rad_s"] == 0.01
    assert state["estimator"] == "kf" and state["estimator_params"] == {"use_foot_force": False}
    assert state["estimator_config"]["use_foot_force"] is False


def test_stand_pd_checks_the_plant_and_rate_options_too(capsys):
    line = usage_error(["stand-pd", "--set", "plant.joint_damping=-1"], capsys)
    assert line.startswith("go2-wbc stand-pd: error: --set plant.joint_damping: expected")


def test_plant_parameters_are_parsed_by_name():
    parser = build_parser()
    args = parser.parse_args(["sit", "--set", "plant.condim=4", "--set",
                              "plant.cone=pyramidal", "--set", "plant.payload_offset_m=0.1,0,-0.02",
                              "--control-rate", "2000", "--physics-dt", "0.0005"])
    assert args.plant_param == [("condim", 4), ("cone", "pyramidal"),
                                ("payload_offset_m", (0.1, 0.0, -0.02))]
    assert isinstance(args.plant_param[0][1], int)  # MuJoCo's condim is an integer
    assert (args.control_rate, args.physics_dt) == (2000.0, 0.0005)


def test_start_up_objects_are_frozen_while_the_loop_runs_and_released_after(monkeypatch):
    import gc

    from sim.control_loop import ControlLoop

    # gc.get_freeze_count() walks every frozen object (40 s over this run's 800 ticks in this
    # process), so it is read only just before each gc.freeze()/gc.unfreeze() once the ticks
    # have begun. Between two such calls the count can only fall (frozen objects freed), so
    # the count at every tick is at least the one read at the call that ends its stretch, and
    # the last call must come after the last tick: the least read is at most the least at any
    # tick, as when it was read at every tick.
    ticks = [0]
    seen: list[int] = []  # the count before each freeze or unfreeze once ticks have begun
    calls_at_tick: list[int] = []
    spin_once = ControlLoop.spin_once

    def counted_spin_once(self):
        ticks[0] += 1
        return spin_once(self)

    def recorded(call):
        def wrapper():
            if ticks[0] > 0:
                seen.append(gc.get_freeze_count())
                calls_at_tick.append(ticks[0])
            call()
        return wrapper

    monkeypatch.setattr(ControlLoop, "spin_once", counted_spin_once)
    monkeypatch.setattr(gc, "freeze", recorded(gc.freeze))
    monkeypatch.setattr(gc, "unfreeze", recorded(gc.unfreeze))
    before = gc.get_freeze_count()
    code, _ = run(["stand", "--duration", "0.5"])
    assert code == EXIT_SUCCEEDED
    assert ticks[0] > 0 and calls_at_tick and calls_at_tick[-1] == ticks[0]
    assert min(seen) > before + 100_000  # the models, MuJoCo, numba's code: out of every scan
    assert gc.get_freeze_count() == before  # given back when the run ends


def test_a_mujoco_gl_that_mujoco_rejects_is_one_line_and_exit_4():
    # MuJoCo reads MUJOCO_GL when first imported: a fresh interpreter.
    env = {**os.environ, "MUJOCO_GL": "bogus"}
    done = subprocess.run(
        [sys.executable, "-c", ("import sys; from sim.cli import main; "
                                "sys.exit(main(['high-five', '--hold', '0']))")],
        cwd=Path(__file__).resolve().parents[1], env=env, capture_output=True, text=True,
        timeout=120, check=False)
    assert done.returncode == EXIT_UNAVAILABLE, done.stderr
    assert done.stderr.strip() == (
        "go2-wbc: invalid value for environment variable MUJOCO_GL: bogus; unset it, or set "
        "one MuJoCo knows (egl, osmesa, glfw)")
