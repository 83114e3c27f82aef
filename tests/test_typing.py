"""The public names are typed for a user's type checker: mypy on a small user script."""

from __future__ import annotations

import importlib
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import NamedTuple

import pytest

ROOT = Path(__file__).resolve().parents[1]
USER_SCRIPT = ROOT / "tests" / "data" / "typed_user_script.py"
#: The packages whose ``__all__`` a user imports from.
PUBLIC_PACKAGES = ("wbc", "wbc.backends", "tasks", "actions", "actions.robot")
REVEALED = re.compile(r'^(?P<path>.+?):(?P<line>\d+): note: Revealed type is "(?P<type>.*)"$')
EXPECT = re.compile(r"#\s*expect:\s*(?P<text>.+?)\s*$")


class MypyRun(NamedTuple):
    done: subprocess.CompletedProcess[str]
    every_name: Path
    names: dict[int, str]


def run_mypy(tmp_path: Path, *scripts: Path) -> subprocess.CompletedProcess[str]:
    """mypy on ``scripts`` only: the packages are followed for their types
    (``--follow-imports=silent``) but not judged, so internal gaps do not count here.

    The checkout is on ``MYPYPATH`` (mypy does not see setuptools' editable-install import
    hook); cwd is a temporary directory, away from any project configuration.
    """
    command = [sys.executable, "-m", "mypy", "--follow-imports=silent", "--warn-unused-ignores",
               "--show-error-codes", "--no-color-output", "--cache-dir",
               str(tmp_path / "mypy_cache"), *map(str, scripts)]
    env = {**os.environ, "MYPYPATH": str(ROOT)}
    return subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True,
                          check=False, timeout=120)


def revealed_types(output: str, script: Path) -> dict[int, str]:
    """Line number -> the type mypy revealed there, for ``script``."""
    found = {}
    for line in output.splitlines():
        match = REVEALED.match(line)
        if match and Path(match["path"]).name == script.name:
            found[int(match["line"])] = match["type"]
    return found


def is_any(revealed: str) -> bool:
    """The type is ``Any``, or a callable that returns ``Any``."""
    return revealed == "Any" or revealed.rsplit(" -> ", 1)[-1] == "Any"


def public_names_script(path: Path) -> dict[int, str]:
    """Write a script that reveals every name in the public packages' ``__all__``; returns
    line number -> the name revealed there."""
    lines = ["from typing import reveal_type"]
    names = {}
    for package in PUBLIC_PACKAGES:
        exported = importlib.import_module(package).__all__
        assert len(set(exported)) == len(exported), f"{package}.__all__ repeats a name"
        alias = package.replace(".", "_")
        lines.append(f"import {package} as {alias}")
        for name in exported:
            lines.append(f"reveal_type({alias}.{name})")
            names[len(lines)] = f"{package}.{name}"
    path.write_text("\n".join(lines) + "\n")
    return names


@pytest.fixture(scope="module")
def mypy_run(tmp_path_factory: pytest.TempPathFactory) -> MypyRun:
    if importlib.util.find_spec("mypy") is None:
        pytest.fail("mypy is not installed here: `make install` installs the test extra")
    tmp_path = tmp_path_factory.mktemp("typing")
    every_name = tmp_path / "every_public_name.py"
    names = public_names_script(every_name)
    return MypyRun(run_mypy(tmp_path, USER_SCRIPT, every_name), every_name, names)


def test_the_user_script_type_checks(mypy_run: MypyRun) -> None:
    done = mypy_run.done
    # --warn-unused-ignores: a deliberate mistake in the script that mypy did not catch
    # (an untyped name) is an error too.
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Success: no issues found in 2 source files" in done.stdout


def test_the_user_script_sees_the_public_names_typed(mypy_run: MypyRun) -> None:
    done = mypy_run.done
    expected = {number: EXPECT.search(line)["text"]
                for number, line in enumerate(USER_SCRIPT.read_text().splitlines(), start=1)
                if line.startswith("reveal_type(") and EXPECT.search(line)}
    assert len(expected) >= 10
    revealed = revealed_types(done.stdout, USER_SCRIPT)
    assert sorted(revealed) == sorted(expected), done.stdout
    wrong = {number: (revealed[number], text) for number, text in expected.items()
             if is_any(revealed[number]) or text not in revealed[number]}
    assert not wrong, f"line: (revealed, expected to contain): {wrong}"


def test_every_public_name_is_typed(mypy_run: MypyRun) -> None:
    revealed = revealed_types(mypy_run.done.stdout, mypy_run.every_name)
    assert sorted(revealed) == sorted(mypy_run.names), mypy_run.done.stdout
    untyped = sorted(mypy_run.names[number] for number, text in revealed.items() if is_any(text))
    assert not untyped, f"typed as Any for a type checker: {untyped}"
