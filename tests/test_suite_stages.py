"""The suite's two stages: every test listed for the slow stage exists (a renamed or deleted
test would silently fall back to the quick stage), and the list marks what it names."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path

from tests.conftest import ROOT, SLOW_STAGE_LIST, slow_stage_ids

NODE_ID = re.compile(r"^(?P<file>tests/[\w/]+\.py)::(?P<function>\w+)(?P<params>\[.*\])?$")


def _functions(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    return {node.name for node in ast.walk(tree)
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)}


def test_every_listed_slow_test_exists_once():
    ids = slow_stage_ids()
    assert len(ids) == len(set(ids)), "a test is listed twice"
    assert ids, f"{SLOW_STAGE_LIST} lists no test"
    for node_id in ids:
        found = NODE_ID.match(node_id)
        assert found, f"{node_id!r}: not a node id of a test file's function"
        path = ROOT / found["file"]
        assert path.is_file(), f"{node_id!r}: no file {found['file']}"
        assert found["function"] in _functions(path), (
            f"{node_id!r}: {found['file']} defines no {found['function']}")


def test_the_list_marks_its_tests_slow():
    """Collected with ``-m slow``, a listed test's file yields that test; with ``-m "not
    slow"``, not."""
    listed = next(node_id for node_id in slow_stage_ids() if "test_balance_controller" in node_id)
    path = listed.split("::")[0]
    for marks, expected in (("slow", True), ("not slow", False)):
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "--collect-only", "-m",
                               marks, path], cwd=ROOT, capture_output=True, text=True,
                              timeout=300, check=False)
        assert (listed in done.stdout.splitlines()) is expected, done.stdout[-2000:]
