"""The built wheel holds every package and data file, and works from a fresh environment.

The wheel is built offline from a copy of the sources, installed into a new virtual
environment outside the checkout, and used there as a user would: the public API imported,
a short closed-loop high five run, the ``go2-wbc`` command and a type check. The new
environment borrows this one's dependencies through a ``.pth`` file of plain paths, which
leaves this environment's editable install (the checkout's import hook) inactive there.
"""

from __future__ import annotations

import importlib.metadata
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The checkout's top-level packages: what the wheel must hold.
PACKAGES = sorted(p.parent.name for p in ROOT.glob("*/__init__.py"))
#: Not in the wheel: build and editor leftovers.
IGNORED = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info", "build")

PURELIB = "import sysconfig; print(sysconfig.get_path('purelib'))"
#: Run by the fresh environment's interpreter, from a temporary directory.
USER_PROGRAM = """
import json, os, sys
from wbc import (ControllerConfig, Go2Description, InvariantEkf, SensorRecord, StateEstimator,
                 WholeBodyController, available_backends, make_estimator)
from actions import GoalStatus, HighFiveGoal
from sim.control_loop import ControlLoop
import wbc, wbc.backends, tasks, actions, sim, sim.cli, benchmarks

loop = ControlLoop.simulated()
outcome = loop.client("high_five").send_goal_and_wait(
    HighFiveGoal(target_height=0.3, hold_seconds=0), timeout=30.0)
print(json.dumps({
    "files": {m.__name__: m.__file__ for m in (wbc, wbc.backends, tasks, actions, sim,
                                                benchmarks)},
    "sys_path": [os.path.realpath(p) for p in sys.path],
    "status": outcome.status.name,
    "message": outcome.result.message,
    "backends": available_backends(),
}))
"""


def run(command: list[str], *, cwd: Path, env: dict[str, str] | None = None,
        timeout: float = 120) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True,
                          check=False, timeout=timeout)
    program = " ".join(Path(c).name if c.startswith("/") else c for c in command[:4])
    assert done.returncode == 0, f"{program} ... failed:\n{done.stdout}\n{done.stderr[-4000:]}"
    return done


def dependency_paths() -> list[str]:
    """This environment's entries on ``sys.path`` (site-packages and what its ``.pth`` files
    added, such as cmeel's prefix), never the checkout."""
    prefix = Path(sys.prefix).resolve()
    paths = [p for p in sys.path if p and Path(p).is_dir()
             and Path(p).resolve().is_relative_to(prefix) and Path(p).resolve() != ROOT]
    assert paths, f"no site-packages under {prefix} on {sys.path}"
    return paths


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel, built offline with this environment's setuptools from a clean copy of the
    sources (an in-place build would leave build/ in the checkout, shared with other runs)."""
    setuptools = importlib.metadata.version("setuptools")
    if int(setuptools.split(".")[0]) < 77:
        pytest.fail(f"setuptools {setuptools} cannot build this project offline (77 or newer: "
                    "`make install` installs the test extra)")
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, source / name)
    for package in PACKAGES:
        shutil.copytree(ROOT / package, source / package, ignore=IGNORED)
    run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "--no-build-isolation",
         "--no-index", "--disable-pip-version-check", "-q", "-w", str(tmp / "dist")], cwd=tmp)
    (built,) = (tmp / "dist").glob("go2_wbc-*.whl")
    return built


@pytest.fixture(scope="module")
def environment(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A new virtual environment with the wheel installed: its interpreter."""
    venv = tmp_path_factory.mktemp("fresh") / "venv"
    run([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=venv.parent)
    python = venv / "bin" / "python"
    run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps",
         "--no-index", "--disable-pip-version-check", "-q", str(wheel)], cwd=venv.parent)
    site_packages = run([str(python), "-c", PURELIB], cwd=venv.parent).stdout.strip()
    Path(site_packages, "go2_wbc_test_dependencies.pth").write_text(
        "\n".join(dependency_paths()) + "\n")
    return python


def fresh_env() -> dict[str, str]:
    """The environment variables of a user's shell: nothing pointing at the checkout."""
    return {k: v for k, v in os.environ.items()
            if k not in ("PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV", "MYPYPATH")}


def test_the_wheel_holds_every_package_module_and_data_file(wheel: Path) -> None:
    expected = {path.relative_to(ROOT).as_posix()
                for package in PACKAGES for path in (ROOT / package).rglob("*")
                if path.is_file() and "__pycache__" not in path.parts}
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
        (entry_points,) = (archive.read(n).decode() for n in names
                           if n.endswith(".dist-info/entry_points.txt"))
    assert not expected - names, f"missing from the wheel: {sorted(expected - names)}"
    assert {n for n in names if not n.startswith("go2_wbc-")} == expected
    for required in ("wbc/backends/__init__.py", "wbc/py.typed", "tasks/py.typed",
                     "actions/py.typed", "sim/py.typed", "actions/interfaces/HighFive.action",
                     "benchmarks/sweeps/gains.yaml"):
        assert required in names
    assert "go2-wbc = sim.cli:main" in entry_points


# Slow (`make test-slow`): numba compiles every kernel afresh for the new install (~75 s).
# The quick stage still installs the wheel there and runs its command and a type check.
@pytest.mark.slow
def test_a_fresh_environment_runs_a_high_five_from_the_wheel(environment: Path,
                                                            tmp_path: Path) -> None:
    # numba caches compiled kernels by source path: the new install compiles them afresh
    # (about 25 of this run's 30 s), into its own __pycache__.
    done = run([str(environment), "-c", USER_PROGRAM], cwd=tmp_path, env=fresh_env(),
               timeout=300)
    report = json.loads(done.stdout.strip().splitlines()[-1])
    venv = environment.parents[1]
    outside = {module: file for module, file in report["files"].items()
               if not Path(file).is_relative_to(venv)}
    assert not outside, f"imported from outside {venv}: {outside}"
    assert str(ROOT) not in report["sys_path"]
    assert report["status"] == "SUCCEEDED", report["message"]
    assert "daqp" in report["backends"]


def test_the_installed_command_runs(environment: Path, tmp_path: Path) -> None:
    done = run([str(environment.parent / "go2-wbc"), "--help"], cwd=tmp_path,
               env=fresh_env())
    assert done.stdout.startswith("usage: go2-wbc")


def test_a_type_checker_sees_the_installed_packages_typed(environment: Path,
                                                         tmp_path: Path) -> None:
    """mypy finds the installed packages through their ``py.typed`` markers (PEP 561)."""
    script = tmp_path / "user_script.py"
    shutil.copy2(ROOT / "tests" / "data" / "typed_user_script.py", script)
    done = run([sys.executable, "-m", "mypy", "--python-executable", str(environment),
                "--follow-imports=silent", "--warn-unused-ignores", "--no-color-output",
                "--cache-dir", str(tmp_path / "mypy_cache"), str(script)],
               cwd=tmp_path, env=fresh_env())
    constructor = 'Revealed type is "def (config: wbc.controller.controller_config.ControllerConfig'
    assert constructor in done.stdout
    assert 'Revealed type is "Any"' not in done.stdout
