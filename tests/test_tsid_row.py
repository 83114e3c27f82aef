"""The optional TSID row of the QP benchmark: found, or skipped with the reason."""

from __future__ import annotations

import sys

import pytest

from benchmarks.tsid_row import format_tsid_row, tsid_python


def test_a_missing_tsid_interpreter_is_named_in_the_skip_reason(monkeypatch, tmp_path):
    missing = tmp_path / "no-python"
    monkeypatch.setenv("GO2_WBC_TSID_PYTHON", str(missing))
    python, reason = tsid_python()
    assert python is None
    assert str(missing) in reason and "make tsid" in reason
    assert format_tsid_row({"skipped": reason}) == f"TSID: skipped, {reason}"


def test_an_interpreter_without_tsid_is_refused_with_its_import_error(monkeypatch):
    pytest.importorskip("numpy")
    try:
        import tsid  # noqa: F401
    except ImportError:
        pass
    else:  # pragma: no cover - this environment has no TSID by design
        pytest.skip("tsid is importable here")
    monkeypatch.setenv("GO2_WBC_TSID_PYTHON", sys.executable)
    python, reason = tsid_python()
    assert python is None
    assert "cannot import tsid" in reason and "tsid" in reason.split(":")[-1]
