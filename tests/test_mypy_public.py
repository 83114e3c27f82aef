"""CI's type check: mypy on the library's public modules (tests/public_modules.py) reports 0
errors, under pyproject's configuration, which ignores only named untyped dependencies."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.public_modules import LIBRARY, module_path, public_modules

ROOT = Path(__file__).resolve().parents[1]


def test_the_configuration_ignores_no_error_wholesale() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["mypy"]
    assert not {"ignore_missing_imports", "ignore_errors", "follow_imports",
                "disable_error_code"} & set(config)
    for override in config["overrides"]:
        assert set(override) == {"module", "ignore_missing_imports"}, override
        assert not [name for name in override["module"] if name.split(".")[0] in LIBRARY]


def test_the_public_modules_are_the_facades_and_their_homes() -> None:
    modules = public_modules()
    assert {"wbc", "tasks", "actions", "actions.robot", "wbc.backends", "sim.control_loop",
            "wbc.controller.whole_body_controller", "actions.action_client",
            "actions.go2.go2_interfaces", "wbc.controller.tick_plan"} <= set(modules)
    assert len(modules) >= 70 and all(module_path(module).is_file() for module in modules)


@pytest.mark.slow  # mypy over the public modules and what they import: 1 to 2 minutes
def test_mypy_reports_no_error_in_the_public_modules(tmp_path: Path) -> None:
    if importlib.util.find_spec("mypy") is None:
        pytest.skip("mypy is not installed (the test extra installs it)")
    files = [str(module_path(module).relative_to(ROOT)) for module in public_modules()]
    # silent: the modules they import are read for their types, judged only where listed.
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--follow-imports=silent", "--no-color-output",
         "--cache-dir", str(tmp_path / "cache"), *files],
        cwd=ROOT, capture_output=True, text=True, check=False, timeout=900)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.strip() == f"Success: no issues found in {len(files)} source files"
