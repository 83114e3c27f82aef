"""The run's recording (actions.robot.run_recording, run_channels, joint_frames) and its reading
back (sim.recorded_run, go2-wbc replay), on synthetic snapshots: no simulation."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from mcap.reader import make_reader

from actions.robot.joint_frames import JointFrames
from actions.robot.run_channels import JSON_CHANNELS, RunChannels
from actions.robot.run_recording import RunRecording, Snapshot
from sim.cli import main
from sim.recorded_run import RecordingError, load_run
from tests.conftest import random_configuration
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS

#: Every channel a recording has, with its schema.
SCHEMAS = {"/tf": "foxglove.FrameTransforms", "/joint_states": "foxglove.JointStates",
           "/markers": "foxglove.SceneUpdate", "/log": "foxglove.Log",
           "/robot_description": "std_msgs/msg/String",
           **{topic: name for topic, (name, _) in JSON_CHANNELS.items()}}
PERIOD_S = 1e-3
METADATA = {"command": "test", "plant": "menagerie", "state": "estimate", "estimator": "kf",
            "control_rate_hz": "1000"}


def snapshot(t_s: float, q: np.ndarray, *, truth: bool = True, raised: bool = False) -> Snapshot:
    """A standing robot's snapshot at ``t_s`` [s], its FR foot raised to a target if asked."""
    targets = np.full((4, 3), np.nan)
    feet = np.array([[0.19, 0.14, 0.02], [0.19, -0.14, 0.02], [-0.19, 0.14, 0.02],
                     [-0.19, -0.14, 0.02]])
    if raised:
        targets[1] = [0.3, -0.15, 0.4]
        feet[1] = [0.3, -0.15, 0.39]
    return Snapshot(
        t_s=t_s, q=q.copy(), v=np.zeros(18), tau=np.arange(12.0), foot_target=targets,
        stance=(True, not raised, True, True), tick_us=250.0, qp_ok=True, status="OK",
        phase="holding" if raised else "shifting", estimate_contact=np.ones(4),
        q_true=q.copy() if truth else None, v_true=np.zeros(18) if truth else None,
        force_n=np.tile([0.0, 0.0, 37.5], (4, 1)) if truth else None,
        foot_position=feet if truth else None, com_margin_m=0.03 if truth else math.nan,
        raised_leg="FR")


@pytest.fixture(scope="module")
def standing(description) -> np.ndarray:
    return description.pose("standing")


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, standing) -> Path:
    """25 snapshots at 50 Hz (0.48 s), the last 10 with the foot raised, and two lines."""
    path = tmp_path_factory.mktemp("rec") / "run.mcap"
    recording = RunRecording(RunChannels(mcap_path=path, metadata=METADATA),
                             control_period_s=PERIOD_S)
    recording.line("state: test", 0.0)
    for k in range(25 * recording.decimation):
        if recording.due():
            recording.capture(snapshot(k * PERIOD_S, standing, raised=k >= 300))
            recording.drain()
    recording.feedback("holding", 0.5, 0.3)
    recording.line("result: SUCCEEDED", 0.48)
    recording.close()
    return path


def test_a_recording_lists_every_channel_with_its_schema_counts_and_the_urdf(recorded,
                                                                           description):
    with recorded.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        schemas = {c.topic: summary.schemas[c.schema_id].name
                   for c in summary.channels.values()}
        counts = {summary.channels[cid].topic: n
                  for cid, n in summary.statistics.channel_message_counts.items()}
        attachments = {a.name: a.data for a in reader.iter_attachments()}
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
        description_data = [json.loads(m.data)["data"] for _, _, m in
                            reader.iter_messages(topics=["/robot_description"])]
    assert schemas == SCHEMAS
    for topic in ("/tf", "/joint_states", "/markers", "/plot", "/contacts",
                  "/controller/timing", "/wbc/state"):
        assert counts[topic] == 25, topic
    assert counts["/log"] == 2 and counts["/action/feedback"] == 1
    assert counts["/robot_description"] == 1  # once a second of robot time: 0.48 s
    assert attachments["go2.urdf"] == description.urdf_path.read_bytes()
    assert metadata["go2-wbc"] == METADATA
    assert "<robot" in description_data[0] and "package://" not in description_data[0]
    assert description.package_share_dir.as_uri() in description_data[0]
    assert summary.statistics.message_end_time == round(0.48 * 1e9)


def test_the_recording_reads_back_as_the_plot_s_arrays(recorded, standing):
    run = load_run(recorded)
    assert run.kind == "mcap" and run.simulated
    assert run.arrays["t_s"] == pytest.approx(np.arange(25) * 0.02)
    np.testing.assert_allclose(run.arrays["q_true"][-1], standing, atol=1e-6)
    # The raised leg's target (NaN while it stood) and measured position.
    assert np.isnan(run.arrays["foot_target"][0]).all()
    np.testing.assert_allclose(run.arrays["foot_target"][-1], [0.3, -0.15, 0.4])
    assert run.arrays["contact_forces"].shape == (25, 4, 3)
    assert list(run.arrays["phase"][[0, -1]]) == ["shifting", "holding"]
    # The control period from the metadata (the rows are 50 Hz snapshots), the plot's caption.
    assert float(run.arrays["control_period_s"]) == PERIOD_S
    assert run.caption() == "plant menagerie, control 1000 Hz; state estimated by kf"
    assert run.describe() == (f"{recorded}: MCAP, 10 channels, {len(run.messages)} messages, "
                              "25 states over 0.480 s, simulated")


def test_joint_frames_compose_to_pinocchio_s_link_placements(model):
    frames = JointFrames(model_urdf := _urdf())
    assert model_urdf.name == "go2.urdf"
    rng = np.random.default_rng(3)
    data = model.createData()
    for _ in range(3):
        q = random_configuration(model, rng)
        pin.forwardKinematics(model, data, q)
        rotations = frames.rotations(q[7:])
        placements = {"base": pin.XYZQUATToSE3(q[:7])}
        for k, name in enumerate(JOINT_NAMES):
            x, y, z, w = rotations[k]
            local = pin.SE3(pin.Quaternion(w, x, y, z).matrix(), frames.origin_xyz[k])
            placements[frames.children[k]] = placements[frames.parents[k]] * local
            expected = data.oMi[model.getJointId(name)]
            np.testing.assert_allclose(placements[frames.children[k]].homogeneous,
                                       expected.homogeneous, atol=1e-9, err_msg=name)


def _urdf() -> Path:
    from wbc.model.description import Go2Description

    return Go2Description.default().urdf_path


def test_snapshots_are_taken_every_decimation_th_tick_and_a_full_queue_drops(tmp_path,
                                                                            standing):
    recording = RunRecording(RunChannels(mcap_path=tmp_path / "d.mcap"),
                             control_period_s=2e-3, rate_hz=100.0, queue_size=3)
    assert recording.decimation == 5 and recording.rate_hz == 100.0
    assert [recording.due() for _ in range(11)] == [True, False, False, False, False] * 2 + [
        True]
    for k in range(5):
        recording.capture(snapshot(k * 0.01, standing, truth=False))
    assert (recording.taken, recording.dropped) == (5, 2)
    recording.close()
    assert recording.logged == 3


def test_drain_logs_only_what_fits_the_time_left_and_an_outlier_fades(tmp_path, standing):
    now = [0.0]

    def clock() -> float:
        now[0] += 1e-4  # each reading: 0.1 ms later
        return now[0]

    recording = RunRecording(RunChannels(mcap_path=tmp_path / "t.mcap"),
                             control_period_s=PERIOD_S)
    recording.capture(snapshot(0.0, standing))
    assert recording.drain(1.0, clock=clock) == 1  # 5 steps, each seen to take 0.1 ms
    assert recording._expected_s == pytest.approx([1e-4] * 5)
    recording.capture(snapshot(0.02, standing))
    assert recording.drain(0.5e-4, clock=clock) == 0  # not even one step fits
    assert recording._expected_s[0] == pytest.approx(0.95e-4)
    assert recording.drain(1.0, clock=clock) == 1
    recording.close()


def test_a_bad_rate_or_no_sink_is_refused_naming_it(tmp_path):
    channels = RunChannels(mcap_path=tmp_path / "r.mcap")
    with pytest.raises(ConfigurationError,
                       match=r"recording rate_hz: expected a rate in \(0, 500\] \[Hz\], "
                             r"received 600.0"):
        RunRecording(channels, control_period_s=2e-3, rate_hz=600.0)
    channels.close()
    with pytest.raises(ConfigurationError, match="expected an mcap_path, a port or both"):
        RunChannels()


def test_replay_of_a_recording_exits_0_and_bad_files_get_one_line(recorded, tmp_path,
                                                                  capsys):
    assert main(["replay", str(recorded), "--headless"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].endswith("25 states over 0.480 s, simulated")
    truncated = tmp_path / "cut.mcap"
    truncated.write_bytes(recorded.read_bytes()[:4000])
    foreign = tmp_path / "notes.mcap"
    foreign.write_text("hello\n")
    npz = tmp_path / "other.npz"
    np.savez(npz, x=np.zeros(3))
    for path, problem in (
            (truncated, "truncated MCAP file (4000 bytes, no closing magic"),
            (foreign, "not an MCAP recording or an .npz log (it starts with b'hello\\n'"),
            (npz, "not a go2-wbc --log file (no t_s, q, v array; it holds x)"),
            (tmp_path / "none.mcap", "cannot read it (No such file or directory)")):
        assert main(["replay", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and problem in err, err
        assert err.startswith(f"go2-wbc: replay: {path}: ")


def test_an_mcap_without_the_state_channel_is_named_foreign(tmp_path):
    path = tmp_path / "other.mcap"
    channels = RunChannels(mcap_path=path)
    channels.log_description(0)
    channels.close()
    with pytest.raises(RecordingError, match=r"without go2-wbc's /wbc/state channel "
                                             r"\(channels: /robot_description\)"):
        load_run(path)


def test_a_robot_s_recording_refuses_plot_naming_why(tmp_path, standing, capsys):
    path = tmp_path / "robot.mcap"
    recording = RunRecording(RunChannels(mcap_path=path), control_period_s=PERIOD_S)
    recording.capture(snapshot(0.0, standing, truth=False))
    recording.close()
    assert not load_run(path).simulated
    assert main(["replay", str(path), "--plot", str(tmp_path / "p.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds no simulator truth (a robot's run)" in err
    assert LEGS == ("FL", "FR", "RL", "RR")  # the snapshot's rows
