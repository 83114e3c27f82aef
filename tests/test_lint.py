"""The checkout passes ``ruff check .`` with pyproject.toml's rules, as ``make lint`` runs it."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.skipif(importlib.util.find_spec("ruff") is None,
                    reason="ruff is not installed: pip install -e '.[test]' (it pins ruff)")
def test_ruff_check_passes() -> None:
    # This interpreter's ruff (the pinned one) from the repository root, so that ruff reads
    # pyproject.toml's [tool.ruff] and its excludes.
    done = subprocess.run([sys.executable, "-m", "ruff", "check", "."], cwd=ROOT,
                          capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 0, f"ruff check . failed:\n{done.stdout}{done.stderr}"
