"""A walk's recording: ``/walking`` (commanded and measured velocity in the heading frame, swing
and loaded feet) and the command in ``/wbc/state``, read back as the walking plot's arrays; on
synthetic snapshots and ``run --dds``'s frame (quick), a simulated ``go2-wbc walk --mcap``
replayed with ``--plot``, and ``run --dds --mcap`` walked by ``rt/cmd_vel`` (slow: closed
loops)."""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from actions.robot.recording_process import SnapshotFrame, pack_snapshot, unpack_snapshot
from actions.robot.run_channels import RunChannels
from actions.robot.run_recording import RunRecording, WalkSample
from benchmarks.dds_outputs import TruthMonitor, standing
from benchmarks.dds_processes import CONTROLLER_READY, DdsProcesses, private_domain_id
from sim.cli import main
from sim.cli.exit_codes import EXIT_INTERRUPTED, EXIT_SUCCEEDED
from sim.gait_view import heading_velocities
from sim.recorded_run import load_run
from sim.walking_plot import walked
from tests.test_recording import METADATA, PERIOD_S, snapshot
from wbc.model.description import LEGS
from wbc.robot_io.dds.cmd_vel_topic import CmdVelWriter
from wbc.robot_io.dds.domain_config import join_domain

#: The simulated walk: forward [m/s] for this long [s] (then the stop, on four feet).
FORWARD_MPS, WALK_S = 0.3, 0.8


def messages(path: Path, topic: str) -> list[tuple[int, dict]]:
    """``(log time [ns], message)`` of a JSON channel, in time order."""
    with path.open("rb") as f:
        return [(m.log_time, json.loads(m.data)) for _, _, m in
                make_reader(f).iter_messages(topics=[topic], log_time_order=True)]


def kept_figures(monkeypatch: pytest.MonkeyPatch) -> list:
    """The figures ``--plot`` draws from now on (``sim.run_plot.plot_figure``'s), kept."""
    import sim.run_plot

    figures = []
    original = sim.run_plot.plot_figure

    def keep(*args, **kwargs):
        figures.append(original(*args, **kwargs))
        return figures[-1]

    monkeypatch.setattr(sim.run_plot, "plot_figure", keep)
    return figures


def schema_of(path: Path, topic: str) -> str | None:
    """The schema name of ``topic`` in the file's summary (``None``: no such channel)."""
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    return next((summary.schemas[c.schema_id].name for c in summary.channels.values()
                 if c.topic == topic), None)


def test_walk_samples_go_on_walking_and_read_back_as_the_command_nan_elsewhere(
        tmp_path, description):
    """10 snapshots, the middle 4 walking: 4 /walking messages with the numbers given, the
    command read back where it was and NaN where nothing walked."""
    standing = description.pose("standing")
    path = tmp_path / "walk.mcap"
    recording = RunRecording(RunChannels(mcap_path=path, metadata=METADATA),
                             control_period_s=PERIOD_S)
    walking = range(3, 7)
    for k in range(10 * recording.decimation):
        if recording.due():
            s = snapshot(k * PERIOD_S, standing)
            i = k // recording.decimation
            if i in walking:
                s.walk = WalkSample(
                    commanded=np.array([0.1 * i, -0.05, 0.2]),
                    measured=np.array([0.1 * i - 0.01, 0.0, 0.19]),
                    measured_true=np.array([0.1 * i - 0.02, 0.01, 0.18]),
                    swing_legs=("FR", "RL"), loaded=(True, False, False, True))
            recording.capture(s)
            recording.drain()
    recording.close()
    walk = messages(path, "/walking")
    assert schema_of(path, "/walking") == "go2_wbc.Walking"
    assert [t for t, _ in walk] == [round(i * 0.02 * 1e9) for i in walking]
    first = walk[0][1]
    assert first["commanded"] == pytest.approx(
        {"forward_mps": 0.3, "lateral_mps": -0.05, "yaw_rate_radps": 0.2})
    assert first["measured"] == pytest.approx(
        {"forward_mps": 0.29, "lateral_mps": 0.0, "yaw_rate_radps": 0.19})
    assert first["measured_true"]["forward_mps"] == pytest.approx(0.28)
    assert first["swing_legs"] == ["FR", "RL"] and first["legs"] == list(LEGS)
    assert first["loaded"] == [True, False, False, True]
    arrays = load_run(path).arrays
    assert walked(arrays)
    commanded = arrays["commanded_velocity"]
    assert np.isnan(commanded[[0, 1, 2, 7, 8, 9]]).all()
    np.testing.assert_allclose(commanded[3:7, 0], [0.3, 0.4, 0.5, 0.6])
    np.testing.assert_allclose(commanded[3:7, 1:], [[-0.05, 0.2]] * 4)


def test_a_recording_that_never_walks_has_no_walking_channel_nor_command(tmp_path,
                                                                        description):
    path = tmp_path / "stand.mcap"
    recording = RunRecording(RunChannels(mcap_path=path), control_period_s=PERIOD_S)
    recording.capture(snapshot(0.0, description.pose("standing")))
    recording.close()
    assert schema_of(path, "/walking") is None
    arrays = load_run(path).arrays
    assert "commanded_velocity" not in arrays and not walked(arrays)


@pytest.fixture(scope="module")
def walk_recording(tmp_path_factory) -> Path:
    """``go2-wbc walk --forward 0.3 --duration 0.8 --mcap``: simulated, headless, 1 kHz."""
    path = tmp_path_factory.mktemp("walk") / "walk.mcap"
    code = main(["walk", "--forward", f"{FORWARD_MPS:g}", "--duration", f"{WALK_S:g}",
                 "--mcap", str(path)])
    assert code == EXIT_SUCCEEDED
    return path


@pytest.mark.slow
def test_a_recorded_walk_carries_its_command_and_replays_as_the_walking_plot(
        walk_recording, tmp_path, monkeypatch, capsys):
    walk = messages(walk_recording, "/walking")
    states = messages(walk_recording, "/wbc/state")
    commanded = np.array([[m["commanded"][k] for k in ("forward_mps", "lateral_mps",
                                                       "yaw_rate_radps")] for _, m in walk])
    # The command ramps up (2 m/s^2), holds what was asked, and ramps down at the stop.
    assert commanded[:, 0].max() == pytest.approx(FORWARD_MPS, abs=1e-9)
    assert np.all(commanded[:, 0] >= 0.0) and not np.any(commanded[:, 1:])
    held = np.array([abs(c - FORWARD_MPS) < 1e-9 for c in commanded[:, 0]])
    assert held.sum() * 0.02 >= WALK_S - 0.3  # 50 Hz snapshots at the command
    # /walking is logged with the states that walked, and says what /wbc/state holds.
    by_time = dict(states)
    assert all(by_time[t]["commanded_velocity"] is not None for t, _ in walk)
    assert sum(s["commanded_velocity"] is not None for _, s in states) == len(walk)
    for t, m in walk[::10]:
        s = by_time[t]
        truth = heading_velocities(np.array(s["q_true"]), np.array(s["v_true"]))
        assert [m["measured_true"][k] for k in ("forward_mps", "lateral_mps",
                                                "yaw_rate_radps")] == pytest.approx(
            truth.tolist(), abs=1e-5)
        assert len(m["loaded"]) == 4 and set(m["swing_legs"]) <= set(LEGS)
    # It walked: the truth's forward velocity while the command held, and some swing; the
    # motion's own measure (its CoM, estimated) agrees with the truth's base on average.
    measured = np.array([m["measured_true"]["forward_mps"] for _, m in walk])[held]
    motion = np.array([m["measured"]["forward_mps"] for _, m in walk])[held]
    assert motion.mean() == pytest.approx(measured.mean(), abs=0.05)
    with capsys.disabled():  # capsys holds the replay's output below
        print(f"\n/walking: {len(walk)} of {len(states)} states, the command at "
              f"{FORWARD_MPS} m/s in {held.sum()}; the truth's forward velocity then "
              f"{measured.mean():.3f} m/s on average, the motion's {motion.mean():.3f}; "
              f"{walk_recording.stat().st_size} bytes")
    assert 0.5 * FORWARD_MPS < measured.mean() < 1.5 * FORWARD_MPS
    assert any(m["swing_legs"] for _, m in walk)
    assert any(not all(m["loaded"]) for _, m in walk)

    figures = kept_figures(monkeypatch)
    png = tmp_path / "walk.png"
    assert main(["replay", str(walk_recording), "--headless", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
    assert f"wrote {png}" in capsys.readouterr().out
    (figure,) = figures
    axes = figure.axes
    assert [ax.get_ylabel() for ax in axes[:3]] == [
        "forward [m/s]", "lateral [m/s]", "yaw rate [rad/s]"]
    (line,) = [ln for ln in axes[0].get_lines() if ln.get_label() == "commanded"]
    plotted = np.asarray(line.get_ydata(), dtype=float)
    assert len(plotted) == len(states)
    assert np.nanmax(plotted) == pytest.approx(FORWARD_MPS, abs=1e-9)
    # The plotted command is /walking's, state by state.
    np.testing.assert_allclose(plotted[np.isfinite(plotted)], commanded[:, 0], atol=1e-6)


def test_a_live_client_is_told_of_walking_when_it_first_walks_and_receives_it():
    """``/walking`` is advertised to a client already connected when the walk begins (the
    channel is made then), and its messages reach the client as logged."""
    import asyncio

    import websockets
    from websockets.typing import Subprotocol

    from tests.test_recording_live import SUBPROTOCOL

    channels = RunChannels(port=0)
    message = {"commanded": {"forward_mps": 0.3, "lateral_mps": 0.0, "yaw_rate_radps": 0.0},
               "measured": None, "measured_true": None, "swing_legs": ["FL", "RR"],
               "legs": list(LEGS), "loaded": None}

    async def client() -> tuple[str, dict]:
        async with websockets.connect(f"ws://127.0.0.1:{channels.port}",
                                      subprotocols=[Subprotocol(SUBPROTOCOL)],
                                      max_size=None) as ws:
            async def next_json(op: str) -> dict:
                while True:
                    frame = await asyncio.wait_for(ws.recv(), 10.0)
                    if isinstance(frame, str) and json.loads(frame)["op"] == op:
                        return json.loads(frame)

            await next_json("advertise")  # the channels made with the recording
            channels.log_walking(message, 0)
            advertised = (await next_json("advertise"))["channels"]
            (walking,) = [c for c in advertised if c["topic"] == "/walking"]
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": 1, "channelId": walking["id"]}]}))
            for k in range(1, 200):  # until the subscription is in place
                channels.log_walking(message, k * 20_000_000)
                try:
                    frame = await asyncio.wait_for(ws.recv(), 0.05)
                except TimeoutError:
                    continue
                if isinstance(frame, bytes) and frame[0] == 1:
                    return walking["schemaName"], json.loads(frame[13:])
            raise AssertionError("no /walking message reached the client")

    try:
        schema, received = asyncio.run(client())
    finally:
        channels.close()
    assert schema == "go2_wbc.Walking"
    assert received == message


def test_a_walk_survives_run_dds_s_frame(description):
    """The frame carries the command and the motion's measured velocity; the swing legs are
    the schedule's legs out of stance; a robot's run has no truth to add."""
    s = snapshot(0.5, description.pose("standing"), truth=False)
    s.stance = (False, True, True, False)
    s.walk = WalkSample(commanded=np.array([0.3, -0.1, 0.4]),
                        measured=np.array([0.28, -0.09, 0.41]), swing_legs=("FL", "RR"))
    back = unpack_snapshot(pack_snapshot(s, SnapshotFrame()))
    assert back.walk is not None
    np.testing.assert_array_equal(back.walk.commanded, [0.3, -0.1, 0.4])
    np.testing.assert_array_equal(back.walk.measured, [0.28, -0.09, 0.41])
    assert back.walk.swing_legs == ("FL", "RR")
    assert back.walk.measured_true is None and back.walk.loaded is None
    s.walk = None
    assert unpack_snapshot(pack_snapshot(s, SnapshotFrame())).walk is None


@pytest.mark.slow
def test_run_dds_mcap_of_a_cmd_vel_walk_carries_the_command(tmp_path):
    """bridge + ``run --dds --mcap`` + ``rt/cmd_vel`` at 0.3 m/s, 20 Hz for 1.5 s, then
    nothing: ``/walking`` holds the command, the motion's measured velocity and the swing
    legs, from the stream's walk to its stop."""
    mcap = tmp_path / "controller.mcap"
    with DdsProcesses(tmp_path, domain_id=private_domain_id(13)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        bridge = run.bridge(log=False, report=False)
        controller = run.controller("--mcap", str(mcap), log=False, wait=False)
        controller.wait_for_line(CONTROLLER_READY, timeout_s=600.0)  # a cold numba cache
        truth.wait_for(standing, timeout_s=15.0, hold_s=0.5, what="the robot standing")
        dds = join_domain(run.interface, domain_id=run.domain_id)
        writer = CmdVelWriter(dds)
        try:
            assert writer.wait_for_reader(10.0)
            for _ in range(30):  # 1.5 s at 20 Hz, on the wall clock (as teleop --dds)
                writer.publish(FORWARD_MPS, 0.0, 0.0)
                time.sleep(0.05)
            truth.wait_for(standing, timeout_s=10.0, hold_s=0.5,
                           what="the robot standing after the timeout")
        finally:
            writer.close()
            dds.close()
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
    walk = messages(mcap, "/walking")
    states = messages(mcap, "/wbc/state")
    assert schema_of(mcap, "/walking") == "go2_wbc.Walking"
    commanded = np.array([m["commanded"]["forward_mps"] for _, m in walk])
    measured = np.array([m["measured"]["forward_mps"] for _, m in walk])
    held = np.abs(commanded - FORWARD_MPS) < 1e-9
    print(f"\nrun --dds --mcap, rt/cmd_vel at {FORWARD_MPS} m/s for 1.5 s: /walking in "
          f"{len(walk)} of {len(states)} states, the command held in {held.sum()}, the "
          f"motion's measured forward velocity then {measured[held].mean():.3f} m/s")
    assert commanded.max() == pytest.approx(FORWARD_MPS, abs=1e-9)
    assert held.sum() >= 60  # about 100: 1.5 s of commands and the 0.5 s timeout, less the ramp
    assert not any(m["commanded"]["lateral_mps"] or m["commanded"]["yaw_rate_radps"]
                   for _, m in walk)
    assert 0.5 * FORWARD_MPS < measured[held].mean() < 1.5 * FORWARD_MPS
    assert any(m["swing_legs"] for _, m in walk)
    assert all(m["measured_true"] is None and m["loaded"] is None for _, m in walk)
    # /wbc/state says the same command at the same instants, null before and after.
    by_time = dict(states)
    assert all(by_time[t]["commanded_velocity"][0] == pytest.approx(m["commanded"]
                                                                    ["forward_mps"], abs=1e-6)
               for t, m in walk)
    assert sum(s["commanded_velocity"] is not None for _, s in states) == len(walk)
    assert states[0][1]["commanded_velocity"] is None
