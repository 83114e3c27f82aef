"""Types where users type-check: mypy, run from outside the checkout on a user's scripts, finds
the library (the editable install or the wheel), catches a misspelt goal field, and passes the
README's and docs/actions.md's Python blocks."""

from __future__ import annotations

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_BLOCK = re.compile(r"^```python\n(.*?)^```", re.DOTALL | re.MULTILINE)
#: Pages whose Python blocks are client examples, each page's blocks one script.
PAGES = (ROOT / "README.md", ROOT / "docs" / "actions.md")

MISSPELT = '''\
from actions import HIGH_FIVE as HighFive
from actions import ActionClient
from sim.control_loop import ControlLoop

loop = ControlLoop.simulated()
client = ActionClient(loop, HighFive, "high_five")
goal = HighFive.Goal(target_heigth=0.40)
goal.hold_secs = 2
result = client.send_goal_and_wait(HighFive.Goal(target_height=0.4))
print(result.result.mesage)
'''
#: What mypy says of each mistake above, by line.
EXPECTED = {
    7: 'Unexpected keyword argument "target_heigth" for "HighFiveGoal"; did you mean '
       '"target_height"?  [call-arg]',
    8: '"HighFiveGoal" has no attribute "hold_secs"; maybe "hold_seconds"?  [attr-defined]',
    10: '"HighFiveResult" has no attribute "mesage"  [attr-defined]',
}


@pytest.fixture(scope="module")
def mypy_outside(tmp_path_factory: pytest.TempPathFactory) -> tuple[str, Path]:
    """One mypy run in a directory outside the checkout, without MYPYPATH: the library is
    found as installed (a .pth line to the checkout, or the wheel)."""
    if importlib.util.find_spec("mypy") is None:
        pytest.skip("mypy is not installed (the test extra installs it)")
    folder = tmp_path_factory.mktemp("user")
    (folder / "misspelt.py").write_text(MISSPELT)
    # Pinocchio ships no types: a user's own `import pinocchio` needs this line too.
    (folder / "mypy.ini").write_text("[mypy]\n[mypy-pinocchio.*]\nignore_missing_imports = "
                                     "True\n[mypy-pinocchio]\nignore_missing_imports = True\n")
    scripts = ["misspelt.py"]
    for page in PAGES:  # each block a script: each imports what it uses
        for k, block in enumerate(_BLOCK.findall(page.read_text()), start=1):
            name = f"{page.stem.replace('-', '_').lower()}_block_{k}.py"
            (folder / name).write_text(block)
            scripts.append(name)
    env = {key: value for key, value in __import__("os").environ.items()
           if key != "MYPYPATH"}
    done = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-color-output", "--show-error-codes",
         "--cache-dir", str(folder / ".mypy_cache"), *scripts],
        cwd=folder, env=env, capture_output=True, text=True, check=False, timeout=600)
    return done.stdout + done.stderr, folder


@pytest.mark.slow  # one mypy run over the library's types: 10 to 60 s
def test_mypy_outside_the_checkout_sees_the_library(mypy_outside: tuple[str, Path]) -> None:
    output, folder = mypy_outside
    assert ROOT not in folder.resolve().parents
    assert "Cannot find implementation or library stub" not in output, output
    assert "import-not-found" not in output and "import-untyped" not in output, output


@pytest.mark.slow
def test_a_misspelt_field_is_a_type_error(mypy_outside: tuple[str, Path]) -> None:
    output, _ = mypy_outside
    found = {int(line.split(":")[1]): line.split(": error: ", 1)[1]
             for line in output.splitlines() if line.startswith("misspelt.py:")}
    assert found == EXPECTED, output


@pytest.mark.slow
def test_the_docs_client_examples_pass(mypy_outside: tuple[str, Path]) -> None:
    output, _ = mypy_outside
    others = [line for line in output.splitlines()
              if ": error:" in line and not line.startswith("misspelt.py:")]
    assert not others, output
    blocks = sum(len(_BLOCK.findall(page.read_text())) for page in PAGES)
    assert blocks >= 4  # the README's two, the actions page's three
    assert f"Found 3 errors in 1 file (checked {blocks + 1} source files)" in output, output


def pyright_command() -> list[str] | None:
    """pyright as ``make`` installs it (npm, into .venv), or on PATH; None without."""
    local = ROOT / ".venv" / "node_modules" / ".bin" / "pyright"
    if local.exists():
        return [str(local)]
    found = shutil.which("pyright")
    return [found] if found else None


@pytest.mark.slow  # pyright over the library's types: 10 to 60 s
def test_pyright_outside_the_checkout_catches_the_mistakes_and_passes_the_clients(
        tmp_path: Path) -> None:
    """The client examples (the README's first Python block, docs/actions.md's) pass pyright;
    the misspelt script's three mistakes are its three errors."""
    command = pyright_command()
    if command is None:
        pytest.skip("pyright is not installed (make installs it from npm when npm exists)")
    (tmp_path / "misspelt.py").write_text(MISSPELT)
    readme, actions = (_BLOCK.findall(page.read_text()) for page in PAGES)
    clients = [readme[0], *actions]
    for k, block in enumerate(clients, start=1):
        (tmp_path / f"client_{k}.py").write_text(block)
    done = subprocess.run(
        [*command, "--pythonpath", sys.executable, "misspelt.py",
         *(f"client_{k}.py" for k in range(1, len(clients) + 1))],
        cwd=tmp_path, capture_output=True, text=True, check=False, timeout=600)
    errors = [line.strip() for line in done.stdout.splitlines() if " - error: " in line]
    assert [line.split(" - error: ")[0].rsplit("/", 1)[-1] for line in errors] == [
        "misspelt.py:7:22", "misspelt.py:8:6", "misspelt.py:10:21"], done.stdout
    assert 'No parameter named "target_heigth"' in errors[0]
    assert 'Cannot assign to attribute "hold_secs"' in errors[1]
    assert 'Cannot access attribute "mesage"' in errors[2]
    assert "3 errors, 0 warnings" in done.stdout
