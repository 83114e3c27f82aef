"""``--mcap`` on a simulated high five and on ``run --dds``, read back with the ``mcap`` reader;
``go2-wbc replay`` of both kinds of file (slow stage: closed-loop runs)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from benchmarks.dds_outputs import ControllerFigures
from benchmarks.dds_processes import DdsProcesses, private_domain_id
from sim.cli import main
from sim.cli.exit_codes import EXIT_INTERRUPTED, EXIT_SUCCEEDED
from tests.test_recording import SCHEMAS

pytestmark = pytest.mark.slow

#: The channels every snapshot feeds.
PER_SNAPSHOT = ("/tf", "/joint_states", "/markers", "/plot", "/contacts",
                "/controller/timing", "/wbc/state")
#: Snapshots a second (actions.robot.run_recording.DEFAULT_RATE_HZ).
RATE_HZ = 50


def read(path: Path) -> dict:
    """Schemas, counts, attachments, metadata, /log lines, /wbc/state intervals of an MCAP."""
    with path.open("rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        counts = {summary.channels[cid].topic: n
                  for cid, n in summary.statistics.channel_message_counts.items()}
        lines = [m.data for _, c, m in reader.iter_messages(topics=["/log"])]
        state_times = [m.log_time for _, c, m in reader.iter_messages(topics=["/wbc/state"])]
        return {"schemas": {c.topic: summary.schemas[c.schema_id].name
                            for c in summary.channels.values()},
                "counts": counts, "attachments": [a.name for a in reader.iter_attachments()],
                "metadata": {m.name: m.metadata for m in reader.iter_metadata()},
                "lines": lines, "state_dt_s": np.diff(state_times) / 1e9}


@pytest.fixture(scope="module")
def high_five(tmp_path_factory) -> dict:
    """One simulated high five (hold 0 s) with --mcap, --log and --report."""
    tmp = tmp_path_factory.mktemp("hf")
    paths = {name: tmp / f"hf.{name}" for name in ("mcap", "npz", "json")}
    code = main(["high-five", "--hold", "0", "--mcap", str(paths["mcap"]),
                 "--log", str(paths["npz"]), "--report", str(paths["json"])])
    assert code == EXIT_SUCCEEDED
    return {**paths, "file": read(paths["mcap"]), "ticks": len(np.load(paths["npz"])["t_s"]),
            "report": json.loads(paths["json"].read_text())}


def test_high_five_mcap_lists_every_channel_with_counts_of_its_duration_and_rate(high_five):
    file, ticks = high_five["file"], high_five["ticks"]
    assert file["schemas"] == SCHEMAS
    # A snapshot every 20th tick at 1 kHz from the goal's sending on, as --log's rows.
    snapshots = math.ceil(ticks / 20)
    for topic in PER_SNAPSHOT:
        assert file["counts"][topic] == snapshots, topic
    duration_s = (ticks - 1) * 1e-3
    assert snapshots == pytest.approx(duration_s * RATE_HZ + 1, abs=1)
    assert file["counts"]["/action/feedback"] == len(high_five["report"]["feedback"])
    assert file["counts"]["/robot_description"] == math.ceil(duration_s)  # one a second
    assert file["attachments"] == ["go2.urdf"]
    assert file["metadata"]["go2-wbc"]["command"] == "high_five"
    assert file["metadata"]["go2-wbc"]["control_rate_hz"] == "1000"
    assert any(b"result: SUCCEEDED" in line for line in file["lines"])


def test_replay_of_the_mcap_and_the_log_exit_0_and_plot(high_five, tmp_path, capsys):
    png = tmp_path / "replayed.png"
    assert main(["replay", str(high_five["mcap"]), "--headless", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
    assert main(["replay", str(high_five["npz"]), "--headless"]) == 0
    out = capsys.readouterr().out
    assert f"{high_five['npz']}: NPZ, {high_five['ticks']} states" in out
    # Re-served live (fast: 100 times the recorded pace), then exits 0.
    assert main(["replay", str(high_five["mcap"]), "--foxglove", "0", "--speed", "100",
                 "--headless"]) == 0
    out = capsys.readouterr().out
    total = sum(high_five["file"]["counts"].values())
    assert f"{total} messages served" in out


def test_run_dds_mcap_holds_every_channel_at_its_rate(tmp_path):
    mcap = tmp_path / "controller.mcap"
    with DdsProcesses(tmp_path, domain_id=private_domain_id(7)) as run:
        bridge = run.bridge(rate_hz=500, log=False)
        controller = run.controller("--mcap", str(mcap), rate_hz=500, log=False, wait=False)
        controller.wait_for_line(r"^controlling at ", timeout_s=300.0)  # a loaded machine
        client = run.high_five(height_m=0.3, hold_s=0.0)
        assert client.wait(300.0) == EXIT_SUCCEEDED, client.tail()
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        bridge.stop()
    figures = ControllerFigures.read(controller.report_path)
    file = read(mcap)
    # The same channels but the goal's feedback, which goes to the goal's client over DDS.
    assert file["schemas"] == {t: s for t, s in SCHEMAS.items() if t != "/action/feedback"}
    summary = [line for line in controller.output().splitlines() if "snapshots at" in line]
    assert summary and summary[-1].startswith(f"wrote {mcap} (")
    found = re.search(r"\((\d+) snapshots at 50 Hz, (\d+) dropped\)", summary[-1])
    assert found, summary[-1]
    logged, dropped = int(found[1]), int(found[2])
    taken = math.ceil(figures.ticks / 10)  # 500 Hz: every 10th tick
    assert logged + dropped == taken
    assert dropped <= 0.01 * taken, summary[-1]
    for topic in PER_SNAPSHOT:
        assert file["counts"][topic] == logged, topic
    # Every 10th tick of the robot's clock: 20 ms apart (the median: a late tick is late).
    assert np.median(file["state_dt_s"]) == pytest.approx(0.02, abs=2e-4)
    assert any(b"controlling at 500 Hz" in line for line in file["lines"])
    assert file["metadata"]["go2-wbc"]["command"] == "run --dds"
