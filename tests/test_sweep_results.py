"""The JSON Lines results file: appended record by record, read back to resume."""

from __future__ import annotations

import json

import pytest

from benchmarks.sweep_results import SweepResults, SweepResultsError


def record(key: str, outcome: str | None = "S") -> dict:
    if outcome is None:
        return {"key": key, "axes": {}, "error": "RuntimeError: boom", "wall_s": 0.1}
    return {"key": key, "axes": {"pushes.directions_deg": 90.0},
            "result": {"outcome": outcome}, "wall_s": 2.0}


def test_records_are_lines_and_come_back_by_key(tmp_path):
    results = SweepResults(tmp_path / "sub" / "sweep.jsonl")
    assert results.load() == {}
    results.append(record("a"))
    results.append(record("b", "F"))
    lines = results.path.read_text().splitlines()
    assert [json.loads(line)["key"] for line in lines] == ["a", "b"]
    assert results.load() == {"a": record("a"), "b": record("b", "F")}


def test_failed_episodes_are_not_finished_until_a_result_comes(tmp_path):
    results = SweepResults(tmp_path / "sweep.jsonl")
    results.append(record("a", None))
    assert results.load() == {} and results.errors_read == 1
    results.append(record("a", "A"))
    assert results.load() == {"a": record("a", "A")}


def test_an_unfinished_last_line_is_cut_off_and_appending_goes_on(tmp_path):
    results = SweepResults(tmp_path / "sweep.jsonl")
    results.append(record("a"))
    with results.path.open("a") as file:
        file.write('{"key": "b", "axes": {}, "res')  # killed while writing
    assert results.load() == {"a": record("a")} and results.truncated_line
    results.append(record("c"))
    assert list(results.load()) == ["a", "c"] and not results.truncated_line
    assert len(results.path.read_text().splitlines()) == 2


def test_a_whole_last_record_without_its_newline_is_kept(tmp_path):
    results = SweepResults(tmp_path / "sweep.jsonl")
    results.path.write_text(json.dumps(record("a")))
    assert list(results.load()) == ["a"] and not results.truncated_line
    results.append(record("b"))
    assert list(results.load()) == ["a", "b"]


def test_a_damaged_line_before_the_last_is_an_error_naming_it(tmp_path):
    results = SweepResults(tmp_path / "sweep.jsonl")
    results.path.write_text(f"{json.dumps(record('a'))}\nnot json\n{json.dumps(record('b'))}\n")
    with pytest.raises(SweepResultsError, match=r"sweep\.jsonl:2: expected one JSON record with "
                                                r"a 'key' per line, received b'not json'; "
                                                r"remove the line, or start afresh with --fresh"):
        results.load()


def test_clear_starts_afresh(tmp_path):
    results = SweepResults(tmp_path / "sweep.jsonl")
    results.append(record("a"))
    results.clear()
    assert results.load() == {} and not results.path.exists()
