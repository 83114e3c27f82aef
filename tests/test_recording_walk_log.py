"""A walk's ``--log`` (``.npz``) replayed: ``/walking`` rebuilt from the log's columns, the same
messages the walk's ``--mcap`` holds, and the same walking plot (slow: one closed-loop walk
recorded both ways); a log written before those columns replays without ``/walking``, with a
note (quick: synthetic)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from actions.robot.run_channels import RunChannels
from sim.cli import main
from sim.cli.exit_codes import EXIT_SUCCEEDED
from sim.episode_metrics import LOADED_FORCE_N
from sim.gait_view import heading_rad, heading_velocities
from sim.recorded_run import load_run
from sim.run_replay import RunReplay
from tests.test_recording_walk import (
    FORWARD_MPS,
    WALK_S,
    kept_figures,
    messages,
    schema_of,
)
from wbc.model.description import LEGS

#: ``/walking``'s velocity fields, in the arrays' column order.
FIELDS = ("forward_mps", "lateral_mps", "yaw_rate_radps")


def velocity(message: dict, name: str) -> list[float]:
    """``message[name]`` (a ``/walking`` velocity) as (3,) in :data:`FIELDS` order."""
    return [message[name][k] for k in FIELDS]


def replay_to_mcap(npz: Path, mcap: Path) -> None:
    """Replay ``npz`` into an MCAP file through the channels ``replay --foxglove`` serves (no
    pacing: the sleep does nothing)."""
    run = load_run(npz)
    RunReplay(run, speed=100.0, sleep=lambda _s: None).play(
        channels=RunChannels(mcap_path=mcap, metadata={"replay": str(npz)}))


@pytest.fixture(scope="module")
def walk(tmp_path_factory) -> dict:
    """``go2-wbc walk --forward 0.3 --duration 0.8 --mcap --log`` (simulated, 1 kHz, the
    estimate) and its ``.npz`` replayed into an MCAP file: about 8 s."""
    tmp = tmp_path_factory.mktemp("walk_log")
    paths = {"mcap": tmp / "walk.mcap", "npz": tmp / "walk.npz",
             "replayed": tmp / "replayed.mcap"}
    assert main(["walk", "--forward", f"{FORWARD_MPS:g}", "--duration", f"{WALK_S:g}",
                 "--mcap", str(paths["mcap"]), "--log", str(paths["npz"])]) == EXIT_SUCCEEDED
    replay_to_mcap(paths["npz"], paths["replayed"])
    with np.load(paths["npz"]) as data:
        arrays = {name: data[name] for name in data.files}
    return {**paths, "arrays": arrays}


@pytest.mark.slow
def test_a_walk_s_log_replays_with_walking_as_logged_and_as_its_mcap(walk, capsys):
    arrays = walk["arrays"]
    t, commanded = arrays["t_s"], arrays["commanded_velocity"]
    replayed = messages(walk["replayed"], "/walking")
    assert schema_of(walk["replayed"], "/walking") == "go2_wbc.Walking"
    # One message every 20th row (50 Hz at 1 kHz), on each such row that walked.
    rows = [i for i in range(0, len(t), 20) if np.isfinite(commanded[i]).all()]
    assert [ns for ns, _ in replayed] == [round(t[i] * 1e9) for i in rows]
    assert len(rows) >= 70  # 1.5 s of walking, start to stop
    for i, (_, m) in zip(rows, replayed, strict=True):
        assert velocity(m, "commanded") == commanded[i].tolist()
        assert velocity(m, "measured") == arrays["measured_velocity"][i].tolist()
        truth = heading_velocities(arrays["q_true"][i], arrays["v_true"][i])
        np.testing.assert_allclose(velocity(m, "measured_true"), truth, rtol=0, atol=1e-12)
        assert m["swing_legs"] == [leg for leg, on in zip(LEGS, arrays["stance"][i],
                                                          strict=True) if not on]
        assert m["loaded"] == (arrays["contact_forces"][i, :, 2] > LOADED_FORCE_N).tolist()
    # The same messages, at the same instants, as the walk's own --mcap.
    assert replayed == messages(walk["mcap"], "/walking")
    # /wbc/state carries the command on the same rows, null elsewhere.
    states = messages(walk["replayed"], "/wbc/state")
    assert sum(s["commanded_velocity"] is not None for _, s in states) == len(replayed)
    # The numbers are a trot's at the command: while it held 0.3 m/s the truth's forward
    # velocity in the snapshots averages what the true base's displacement over that span
    # gives (0.289 against 0.290 m/s), and the gait swings legs and unloads feet.
    held = [m for _, m in replayed if m["commanded"]["forward_mps"] == FORWARD_MPS]
    held_rows = np.flatnonzero(commanded[:, 0] == FORWARD_MPS)
    first, last = held_rows[0], held_rows[-1]
    yaw = heading_rad(arrays["q_true"][first])
    travelled = ((arrays["q_true"][last, :2] - arrays["q_true"][first, :2])
                 @ [np.cos(yaw), np.sin(yaw)])
    rate = float(travelled / (t[last] - t[first]))
    mean = float(np.mean([m["measured_true"]["forward_mps"] for m in held]))
    motion = float(np.mean([m["measured"]["forward_mps"] for m in held]))
    with capsys.disabled():
        print(f"\nreplayed --log: /walking {len(replayed)} of {len(states)} states, the "
              f"command at {FORWARD_MPS} m/s in {len(held)}; the truth's forward velocity "
              f"{mean:.4f} m/s (its displacement {rate:.4f} m/s), the motion's {motion:.4f}")
    assert len(held) * 0.02 >= WALK_S - 0.3
    assert mean == pytest.approx(rate, abs=0.01)
    assert 0.85 * FORWARD_MPS < mean < 1.1 * FORWARD_MPS
    assert motion == pytest.approx(mean, abs=0.05)
    assert all(m["commanded"]["lateral_mps"] == 0.0 == m["commanded"]["yaw_rate_radps"]
               for m in held)
    assert sum(bool(m["swing_legs"]) for m in held) >= len(held) // 2
    assert any(not all(m["loaded"]) for m in held)


@pytest.mark.slow
def test_a_walk_s_log_plots_the_walking_figure_of_its_mcap(walk, tmp_path, monkeypatch):
    """``replay run.npz --plot``: the walking figure, its command the log's row by row and,
    at the MCAP's states, ``/walking``'s command (which the MCAP's plot draws:
    tests/test_recording_walk.py); its truth the MCAP's ``/wbc/state`` truth."""
    figures = kept_figures(monkeypatch)
    png = tmp_path / "npz.png"
    assert main(["replay", str(walk["npz"]), "--headless", "--plot", str(png)]) == 0
    assert png.stat().st_size > 10_000
    (figure,) = figures
    assert [ax.get_ylabel() for ax in figure.axes[:3]] == [
        "forward [m/s]", "lateral [m/s]", "yaw rate [rad/s]"]
    arrays = walk["arrays"]
    t_ns = np.round(arrays["t_s"] * 1e9).astype(int)
    walking = messages(walk["mcap"], "/walking")
    states = messages(walk["mcap"], "/wbc/state")
    at = np.searchsorted(t_ns, [ns for ns, _ in states])
    assert (t_ns[at] == [ns for ns, _ in states]).all()  # the MCAP's states are log rows
    at_walking = np.searchsorted(t_ns, [ns for ns, _ in walking])
    truth = heading_velocities(np.array([s["q_true"] for _, s in states]),
                               np.array([s["v_true"] for _, s in states]))
    for k, ax in enumerate(figure.axes[:3]):
        lines = {ln.get_label(): np.asarray(ln.get_ydata(), dtype=float)
                 for ln in ax.get_lines()}
        np.testing.assert_array_equal(lines["commanded"], arrays["commanded_velocity"][:, k])
        np.testing.assert_allclose(lines["commanded"][at_walking],
                                   [velocity(m, "commanded")[k] for _, m in walking],
                                   atol=1e-6)
        # The truth each tick, at the MCAP's states: its /wbc/state's (rounded to 1e-6).
        np.testing.assert_allclose(lines["truth (each tick)"][at], truth[:, k], atol=1e-5)


def _old_walk_log(path: Path, standing: np.ndarray, *, drop: tuple[str, ...]) -> None:
    """A 40-row walk's ``--log`` at 1 kHz (commanded 0.2 m/s forward from row 10) without the
    arrays ``drop`` names."""
    n = 40
    arrays = {"t_s": np.arange(n) * 1e-3, "q": np.tile(standing, (n, 1)),
              "v": np.zeros((n, 18)), "q_true": np.tile(standing, (n, 1)),
              "v_true": np.zeros((n, 18)), "contact_forces": np.tile([0.0, 0.0, 35.0],
                                                                     (n, 4, 1)),
              "commanded_velocity": np.full((n, 3), np.nan),
              "measured_velocity": np.full((n, 3), np.nan), "stance": np.ones((n, 4), bool)}
    arrays["commanded_velocity"][10:] = [0.2, 0.0, 0.0]
    arrays["measured_velocity"][10:] = [0.19, 0.0, 0.0]
    np.savez(path, **{k: a for k, a in arrays.items() if k not in drop})


def test_an_old_walk_log_replays_without_walking_and_says_so(tmp_path, description, capsys):
    standing = description.pose("standing")
    old, new = tmp_path / "old.npz", tmp_path / "new.npz"
    _old_walk_log(old, standing, drop=("measured_velocity", "stance"))
    _old_walk_log(new, standing, drop=())
    note = ("old.npz walked but has no measured_velocity or stance array (a --log written "
            "before they were logged): replayed without /walking; --plot draws the walk as "
            "before")
    assert load_run(old).notes == [note]
    assert load_run(new).notes == []
    assert main(["replay", str(old), "--headless"]) == 0
    assert f"replay: note: {note}" in capsys.readouterr().out
    old_mcap, new_mcap = tmp_path / "old.mcap", tmp_path / "new.mcap"
    replay_to_mcap(old, old_mcap)
    replay_to_mcap(new, new_mcap)
    assert schema_of(old_mcap, "/walking") is None
    ((log_ns, line),) = _logs(old_mcap)  # at the first state's time, as a warning
    assert log_ns == 0 and f"replay: note: {note}".encode() in line
    states = messages(old_mcap, "/wbc/state")
    assert len(states) == 2 and all(s["commanded_velocity"] is None for _, s in states)
    # The same log with the columns: /walking on the walking row (row 20 of 0 and 20).
    (walking,) = messages(new_mcap, "/walking")
    assert walking[0] == 20_000_000
    assert velocity(walking[1], "commanded") == [0.2, 0.0, 0.0]
    assert velocity(walking[1], "measured") == [0.19, 0.0, 0.0]
    assert walking[1]["swing_legs"] == [] and walking[1]["loaded"] == [True] * 4
    assert _logs(new_mcap) == []
    # Only one of the two missing: the note names it.
    _old_walk_log(old, standing, drop=("stance",))
    assert load_run(old).notes == [note.replace("measured_velocity or stance", "stance")]
    # A log that never walked (a high five's) has nothing to note.
    _old_walk_log(old, standing, drop=("commanded_velocity", "measured_velocity", "stance"))
    assert load_run(old).notes == []


def _logs(path: Path) -> list[tuple[int, bytes]]:
    """``/log``'s messages (``foxglove.Log``, protobuf: its text is in the bytes) as
    ``(log time [ns], bytes)``."""
    from mcap.reader import make_reader

    with path.open("rb") as f:
        return [(m.log_time, m.data) for _, _, m in
                make_reader(f).iter_messages(topics=["/log"], log_time_order=True)]
