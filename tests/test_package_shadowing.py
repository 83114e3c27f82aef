"""A user's own module named like one of the library's packages: one line naming the file."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from wbc.core.package_shadowing import PACKAGES, PackageShadowedError, check_not_shadowed


def run_script(directory: Path, source: str) -> subprocess.CompletedProcess[str]:
    """Run ``source`` as ``user.py`` in ``directory`` (its directory first on ``sys.path``, as
    for any script), with the installed library."""
    script = directory / "user.py"
    script.write_text(source)
    return subprocess.run([sys.executable, str(script)], cwd=directory, capture_output=True,
                          text=True, check=False, timeout=60)


@pytest.mark.parametrize("name", ["tasks", "sim", "actions", "benchmarks"])
def test_a_module_next_to_the_script_is_named(tmp_path: Path, name: str) -> None:
    (tmp_path / f"{name}.py").write_text("VALUE = 1\n")
    done = run_script(tmp_path, "import wbc\n")
    assert done.returncode == 1
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("wbc.core.package_shadowing.PackageShadowedError: "
                           f"{tmp_path / (name + '.py')} shadows the go2-wbc package '{name}'")
    assert f"rename that file or directory (e.g. my_{name}.py)" in last


def test_a_package_directory_next_to_the_script_is_named(tmp_path: Path) -> None:
    (tmp_path / "tasks").mkdir()
    (tmp_path / "tasks" / "__init__.py").write_text("")
    done = run_script(tmp_path, "from sim.control_loop import ControlLoop\n")
    assert done.returncode == 1
    assert f"{tmp_path / 'tasks' / '__init__.py'} shadows the go2-wbc package 'tasks'" in (
        done.stderr.strip().splitlines()[-1])


def test_without_a_shadowing_module_the_library_imports(tmp_path: Path) -> None:
    (tmp_path / "my_tasks.py").write_text("VALUE = 1\n")
    # The packages that import nothing heavy (tasks and actions load Pinocchio: seconds).
    done = run_script(tmp_path, "import my_tasks\nimport sim, benchmarks, wbc\n"
                                "print(sim.__file__)\n")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().endswith("sim/__init__.py")


def test_an_imported_shadow_is_named_too(monkeypatch: pytest.MonkeyPatch,
                                         tmp_path: Path) -> None:
    """A shadowing module already imported (before the library) is found in sys.modules."""
    fake = type(sys)("benchmarks")
    fake.__file__ = str(tmp_path / "benchmarks.py")
    monkeypatch.setitem(sys.modules, "benchmarks", fake)
    with pytest.raises(PackageShadowedError, match=r"benchmarks\.py shadows the go2-wbc "
                                                   r"package 'benchmarks'"):
        check_not_shadowed()
    check_not_shadowed(tuple(name for name in PACKAGES if name != "benchmarks"))
