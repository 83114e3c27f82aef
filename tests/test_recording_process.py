"""actions.robot.recording_process: a snapshot's frame round trip, and the child process that
writes the MCAP file (counts, lines, drops when the pipe is full, a port it cannot serve)."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import socket
from collections import Counter

import numpy as np
import pytest
from mcap.reader import make_reader

from actions.robot.recording_process import (
    CHILD_NICENESS,
    FRAME_BYTES,
    LINE_BYTES,
    PIPE_BYTES,
    RecordingProcess,
    SnapshotFrame,
    pack_snapshot,
    unpack_snapshot,
)
from actions.robot.tick_stats import SERIES
from sim.cli.recording_options import recording_summary
from tests.test_recording import snapshot
from wbc.core.errors import ConfigurationError


@pytest.fixture(scope="module")
def standing(description) -> np.ndarray:
    return description.pose("standing")


def _equal(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
    return a == b or (a != a and b != b)  # NaN == NaN here


@pytest.mark.parametrize("truth", [True, False])
def test_a_snapshot_survives_its_frame(standing, truth):
    s = dataclasses.replace(snapshot(0.125, standing, truth=truth, raised=True), missed=True,
                            qp_ok=False, stages_us={SERIES[0]: 12.5, "tick": 310.0})
    payload = pack_snapshot(s, SnapshotFrame())
    assert len(payload) + 4 == FRAME_BYTES <= 4096  # PIPE_BUF: a write is all or nothing
    back = unpack_snapshot(payload)
    for field in dataclasses.fields(s):
        assert _equal(getattr(back, field.name), getattr(s, field.name)), field.name


def _topics(path) -> Counter:
    with open(path, "rb") as f:
        return Counter(channel.topic for _, channel, _ in make_reader(f).iter_messages())


@pytest.mark.slow
def test_the_child_writes_every_snapshot_and_line_in_order(tmp_path, standing):
    path = tmp_path / "p.mcap"
    recording = RecordingProcess(mcap_path=path, metadata={"command": "test"},
                                 control_period_s=1e-3)
    assert (recording.decimation, recording.port) == (20, None)
    assert recording.queue_size == PIPE_BYTES // FRAME_BYTES
    # Lower CPU priority than the loop's process (the recording is best effort).
    assert os.getpriority(os.PRIO_PROCESS, recording._process.pid) == min(
        19, os.getpriority(os.PRIO_PROCESS, 0) + CHILD_NICENESS)
    recording.line("first", 0.0)
    for k in range(40):
        if recording.due():
            recording.capture(snapshot(k * 1e-3, standing, truth=False))
    recording.line("last", 0.04)
    recording.close()
    assert (recording.taken, recording.logged, recording.dropped) == (2, 2, 0)
    counts = _topics(path)
    assert counts["/wbc/state"] == counts["/joint_states"] == counts["/tf"] == 2
    with open(path, "rb") as f:
        lines = [json.loads(m.data) if ch.message_encoding == "json" else m.data
                 for _, ch, m in make_reader(f).iter_messages(topics=["/log"])]
        states = [json.loads(m.data) for _, _, m in
                  make_reader(open(path, "rb")).iter_messages(topics=["/wbc/state"])]
    assert [b"first" in m for m in lines] == [True, False]
    assert [b"last" in m for m in lines] == [False, True]
    assert [s["t_s"] for s in states] == [0.0, 0.02]
    assert states[1]["q"] == pytest.approx(standing.tolist(), abs=1e-6)


@pytest.mark.slow
def test_a_full_pipe_drops_snapshots_counted(tmp_path, standing):
    recording = RecordingProcess(mcap_path=tmp_path / "d.mcap", control_period_s=1e-3,
                                 rate_hz=1000.0)
    s = snapshot(0.0, standing)
    # Written far faster than the child builds messages (about 0.3 ms a snapshot): the pipe
    # (about 800 frames) fills and the rest are dropped, without blocking.
    for _ in range(3000):
        recording.capture(s)
    recording.close()
    assert recording.taken == 3000 and recording.dropped > 0
    assert recording.logged + recording.dropped == recording.taken
    assert _topics(tmp_path / "d.mcap")["/wbc/state"] == recording.logged


@pytest.mark.slow
def test_a_busy_port_is_refused_naming_it():
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        with pytest.raises(ConfigurationError, match=f"--foxglove: cannot serve on "
                                                     f"127.0.0.1:{port} .*give another port"):
            RecordingProcess(port=port, control_period_s=1e-3)


def test_a_bad_rate_or_no_sink_is_refused_before_any_process():
    with pytest.raises(ConfigurationError, match=r"rate_hz: expected a rate in \(0, 1000\] "
                                                  r"\[Hz\], received 2000"):
        RecordingProcess(port=0, control_period_s=1e-3, rate_hz=2000.0)
    with pytest.raises(ConfigurationError, match="received neither"):
        RecordingProcess(control_period_s=1e-3)


@pytest.mark.slow
def test_a_child_that_dies_never_stops_the_loop_and_is_said(tmp_path, standing):
    recording = RecordingProcess(mcap_path=tmp_path / "k.mcap", control_period_s=1e-3,
                                 rate_hz=1000.0)
    recording._process.kill()
    recording._process.join(10.0)
    for k in range(5):  # the loop's calls: no exception reaches the tick
        recording.capture(snapshot(k * 1e-3, standing))
        recording.line("still controlling", k * 1e-3)
    recording.close()
    assert recording.taken == 5 and recording.dropped == 5 and recording.logged == 0
    assert recording.error.startswith("the writer process ended (Broken pipe, exit code -9)")
    args = argparse.Namespace(mcap=tmp_path / "k.mcap", foxglove=None)
    assert recording_summary(args, recording) == (
        f"wrote {tmp_path / 'k.mcap'} (0 snapshots at 1000 Hz, 5 dropped); recording "
        f"incomplete: {recording.error}")


@pytest.mark.slow
def test_a_long_line_is_cut_to_fit_one_frame(tmp_path):
    recording = RecordingProcess(mcap_path=tmp_path / "l.mcap", control_period_s=1e-3)
    recording.line("é" * 5000, 0.0)  # 10,000 bytes of UTF-8
    recording.close()
    assert recording.error == ""
    with open(tmp_path / "l.mcap", "rb") as f:
        (log,) = [m.data for _, _, m in make_reader(f).iter_messages(topics=["/log"])]
    assert "é" * (LINE_BYTES // 2) in log.decode(errors="ignore")
    assert "é" * (LINE_BYTES // 2 + 1) not in log.decode(errors="ignore")
