"""Sweeps end to end: serial, process pool and Ray agree; an interrupted sweep resumes."""

from __future__ import annotations

import json
import os
from types import SimpleNamespace

import pytest

from benchmarks import robustness, sweep_runner
from benchmarks.sweep import main, run_sweep
from benchmarks.sweep_results import SweepResults
from benchmarks.sweep_runner import RAY_INSTALL, SweepRunner
from benchmarks.sweep_spec import DIRECTIONS, EpisodeSpec, SweepSpec
from wbc.core.errors import ConfigurationError

PROG = "python -m benchmarks.sweep"
#: The quick sweep's table: 8 N s toward 90 deg is absorbed, toward 315 deg (behind the
#: raised foot's diagonal) the foot goes down, with and without the 2 kg payload.
QUICK_TABLE = ["impulse [N s] | direction [deg]",
               "              |   90  315",
               "            8 |   2S   2A"]
QUICK_TOTALS = "succeeded 2/4 (50 %), aborted 2, fell 0; any fall: no"


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The quick sweep in this process: interrupted before its third episode, then resumed."""
    results = SweepResults(tmp_path_factory.mktemp("serial") / "quick.jsonl")
    spec = SweepSpec.load("quick")
    runs: list[tuple[str, str]] = []
    controllers: list[dict] = []
    messages: list[str] = []
    execute, controller = sweep_runner.execute, robustness.WholeBodyController

    def recorded_controller(**parts):
        controllers.append(parts)
        return controller(**parts)

    def interrupted(episode):
        if len(runs) == 2:
            raise KeyboardInterrupt  # Ctrl-C during the third episode
        runs.append(("first", episode.key))
        return execute(episode)

    def resumed(episode):
        runs.append(("resumed", episode.key))
        return execute(episode)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(robustness, "WholeBodyController", recorded_controller)
        patch.setattr(sweep_runner, "execute", interrupted)
        with pytest.raises(KeyboardInterrupt):
            run_sweep(spec, results, SweepRunner("serial"), progress=False, log=messages.append)
        after_interrupt = results.load()
        patch.setattr(sweep_runner, "execute", resumed)
        run = run_sweep(spec, results, SweepRunner("serial"), progress=False,
                        log=messages.append)
    return SimpleNamespace(spec=spec, results=results, runs=runs, run=run, messages=messages,
                           after_interrupt=after_interrupt, controllers=controllers)


#: What a sweep prints first.
STATE_LINE = ("state: estimate (inekf when estimated), sensors go2; measured on the simulator's "
              "truth")


def by_key(path) -> dict[str, dict]:
    return {r["key"]: r for r in map(json.loads, path.read_text().splitlines())}


def test_an_interrupted_sweep_resumes_without_running_finished_episodes(serial):
    keys = [e.key for e in serial.spec.episodes()]
    assert serial.runs == [("first", keys[0]), ("first", keys[1]),
                           ("resumed", keys[2]), ("resumed", keys[3])]
    assert list(serial.after_interrupt) == keys[:2]
    assert serial.messages == [(f"resuming: 2 of 4 episodes are in {serial.results.path}; "
                                f"running the other 2")]
    assert (serial.run.episodes, serial.run.resumed, serial.run.ran) == (4, 2, 2)
    lines = serial.results.path.read_text().splitlines()
    assert [json.loads(line)["key"] for line in lines] == keys  # each once, in order


def test_the_quick_sweep_runs_its_pushes_plants_and_gains(serial):
    outcomes = {(r["axes"]["plant.payload_kg"], r["axes"][DIRECTIONS]): r["result"]["outcome"]
                for r in serial.run.records.values()}
    assert outcomes == {(0.0, 90.0): "S", (0.0, 315.0): "A", (2.0, 90.0): "S", (2.0, 315.0): "A"}
    for record in serial.run.records.values():
        result = record["result"]
        assert result["standing"] and not result["fell"] and result["qp_failures"] == 0
        assert record["spec"]["controller"]["swing_kp"] == 45.0
        assert record["spec"]["push"]["force_n"] == pytest.approx(80.0)
    # The episode built its controller with the sweep's gain.
    assert serial.controllers == [{"solver": {"control_period_s": 1e-3},
                                   "shaping": {"swing_kp": 45.0}}] * 4
    table = serial.run.report.table().splitlines()
    assert table[3:6] == QUICK_TABLE and table[-1] == QUICK_TOTALS


# Slow (`make test-slow`): worker processes (Ray's start-up) rerun the quick sweep; the
# serial run and its resume are the quick stage's.
@pytest.mark.slow
def test_the_process_pool_gives_the_serial_results(serial, tmp_path, capsys):
    path = tmp_path / "quick.jsonl"
    assert main(["quick", "--executor", "process", "--jobs", "2", "--results", str(path)]) == 0
    out, err = capsys.readouterr()
    assert by_key(path).keys() == by_key(serial.results.path).keys()
    for key, record in by_key(path).items():
        assert record["result"] == serial.run.records[key]["result"], record["axes"]
    lines = out.splitlines()
    assert lines[0] == STATE_LINE
    assert lines[4:7] == QUICK_TABLE and QUICK_TOTALS in lines
    assert "4 episodes: 4 run in " in out and " s wall on process pool (2 processes)" in out
    assert "quick: 100%" in err and "4/4" in err and "fell 0, aborted 2" in err  # the bar
    png = path.with_suffix(".png")
    assert png.read_bytes()[:4] == b"\x89PNG" and f"Wrote {path} and {png}" in out


@pytest.mark.slow
def test_ray_gives_the_serial_results(serial, tmp_path, capsys, monkeypatch):
    ray = pytest.importorskip("ray", reason="Ray is an optional extra: pip install '.[scale]'")
    monkeypatch.setenv("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")  # a local instance on 127.0.0.1
    monkeypatch.setenv("RAY_USAGE_STATS_ENABLED", "0")
    path = tmp_path / "quick.jsonl"
    assert main(["quick", "--executor", "ray", "--jobs", "2", "--no-progress",
                 "--results", str(path)]) == 0
    out = capsys.readouterr().out
    assert not ray.is_initialized()  # shut down
    assert " s wall on Ray (local instance, 2 CPUs)" in out
    for key, record in by_key(path).items():
        assert record["result"] == serial.run.records[key]["result"], record["axes"]
        assert record["worker"].rpartition(":")[2] != str(os.getpid())  # in Ray's workers
    assert len(by_key(path)) == 4 and out.splitlines()[4:7] == QUICK_TABLE


def test_an_episode_that_raises_is_recorded_and_retried_on_resume(tmp_path, monkeypatch,
                                                                   capsys):
    ran = []

    def fake_run(episode):  # no simulation: the bookkeeping only
        ran.append(episode.get(DIRECTIONS))
        if episode.get(DIRECTIONS) == 90.0 and len(ran) < 3:
            raise RuntimeError("boom")
        return {"outcome": "S", "status": "SUCCEEDED", "min_height_m": 0.3, "max_tilt_deg": 1.0}

    monkeypatch.setattr(EpisodeSpec, "run", fake_run)
    args = ["pushes", "--directions", "0,90", "--impulses", "4", "--executor", "serial",
            "--no-progress", "--results", str(tmp_path / "r.jsonl")]
    assert main(args) == 1
    out, err = capsys.readouterr()
    assert "episode pushes.directions_deg=90 failed: RuntimeError: boom" in err
    assert "1 episode raised an error (see 'error' in " in err
    assert err.endswith("; run the same command again to retry it\n")
    assert "succeeded 1/2 (50 %), aborted 0, fell 0; any fall: no; errors 1" in out
    assert main(args) == 0  # only the failed one runs again
    assert ran == [0.0, 90.0, 90.0]
    assert "succeeded 2/2 (100 %)" in capsys.readouterr().out


def test_without_ray_auto_runs_the_process_pool_and_says_how_to_get_ray(monkeypatch, capsys):
    monkeypatch.setattr(sweep_runner, "ray_installed", lambda: False)
    runner = SweepRunner("auto")
    assert runner.executor == "process"
    assert runner.note == ("Ray is not installed: the episodes run in a local process pool. For "
                           f"Ray (every core, or a cluster with --address): {RAY_INSTALL}")
    assert RAY_INSTALL == ("pip install 'go2-wbc[scale]' (in a clone of the repository: "
                           "pip install -e '.[scale]')")
    with pytest.raises(ConfigurationError, match=r"^executor: executor 'ray' needs Ray, which is "
                                                 r"not installed here; pip install"):
        SweepRunner("ray")
    with pytest.raises(SystemExit) as exit_:
        main(["quick", "--address", "auto"])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == (
        f"{PROG}: error: --address: address 'auto' needs Ray, which is not installed here; "
        f"{RAY_INSTALL}, or run executor 'process' (see '{PROG} --help')\n")


def test_an_address_where_no_cluster_listens_is_a_usage_error_at_once(capsys):
    pytest.importorskip("ray", reason="Ray is an optional extra: pip install '.[scale]'")
    with pytest.raises(SystemExit) as exit_:
        main(["quick", "--address", "127.0.0.1:1", "--results", "/nonexistent/quick.jsonl"])
    assert exit_.value.code == 2
    assert capsys.readouterr().err == (
        f"{PROG}: error: --address: cannot connect to a Ray cluster at '127.0.0.1:1' (Connection "
        f"refused); expected the address of a running cluster: auto on one of its nodes, "
        f"HOST:6379, or ray://HOST:10001 (see '{PROG} --help')\n")


@pytest.mark.parametrize(("args", "message"), [
    (["--impulses=-2"], "pushes.impulses_ns: expected a value in [0, inf], received -2"),
    (["--plant", "jont_damping=1"], ("plant.jont_damping: unknown plant parameter 'jont_damping'; "
                                     "valid: preset, joint_damping, joint_friction_loss")),
    (["--gain", "swing_kp=[]"], "gains.swing_kp: expected at least one value, received []"),
    (["--gain", "swing_kp=60:30:0"], ("gains.swing_kp: expected at least one value, received "
                                      "'60:30:0' (an empty range: NUM must be 1 or more)")),
    (["--gain", "swing_kp"], ("--gain: expected NAME=VALUES (e.g. swing_kp=40:60:3), received "
                              "'swing_kp'")),
    (["--jobs", "0"], "--jobs: expected a whole number >= 1, received 0"),
])
def test_a_bad_sweep_is_a_one_line_usage_error(args, message, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["quick", *args])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{PROG}: error: {message}") and err.count("\n") == 1, err
    assert err.endswith(f" (see '{PROG} --help')\n")


def test_a_dry_run_lists_the_fields_and_counts_the_episodes(capsys):
    assert main(["pushes", "--plant", "payload_kg=0,2", "--dry-run"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == STATE_LINE
    assert out[1] == "pushes: 80 episodes"
    assert "  pushes.impulses_ns: 2, 4, 6, 8, 10" in out and "  plant.payload_kg: 0, 2" in out
