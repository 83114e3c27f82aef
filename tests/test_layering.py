"""The floors import one way: no module imports a floor above its own (tests/layering.py)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.layering import (
    FACADES,
    FLOORS,
    PACKAGES,
    floor_of,
    library_modules,
    untolerated_cycles,
    violations,
)

ROOT = Path(__file__).resolve().parents[1]


def test_no_module_imports_a_floor_above_its_own():
    found = violations(ROOT)
    assert not found, "\n".join(map(str, found))


def test_every_module_is_on_a_floor():
    modules = library_modules(ROOT)
    assert len(modules) > 100
    for module in set(modules) - set(FACADES) - set(PACKAGES):
        floor_of(module)  # raises for a module on no floor


def copy_of_the_library(tmp_path: Path) -> Path:
    for package in PACKAGES:
        shutil.copytree(ROOT / package, tmp_path / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    return tmp_path


@pytest.mark.parametrize(("module", "planted", "why"), [
    # the ground floor reaching for the controller
    ("wbc/core/errors.py", "from wbc.controller.controller_config import ControllerConfig",
     "up from 'ground: errors, checks, conventions, compiled helpers' to 'the controller'"),
    # a task reading the controller, inside a function
    ("tasks/com_task.py", "def _late():\n    import wbc.controller.whole_body_controller",
     "up from 'tasks and constraints' to 'the controller'"),
    # the robot loop reaching for the simulator
    ("actions/robot/control_loop.py", "from sim.plant import Plant",
     "up from 'the robot loop' to 'the simulator'"),
    # a library module importing a facade
    ("sim/plant.py", "from wbc import WholeBodyController", "a facade for users"),
])
def test_a_planted_upward_import_is_found(tmp_path, module, planted, why):
    root = copy_of_the_library(tmp_path)
    path = root / module
    path.write_text(path.read_text() + f"\n\n{planted}\n")
    found = violations(root)
    assert len(found) == 1, found
    assert found[0].module == module.removesuffix(".py").replace("/", ".")
    assert why in found[0].why


def test_no_two_library_modules_import_each_other():
    """No import cycle, direct or through other modules, between library modules (the
    command line's included), but inside the packages :data:`TOLERATED_CYCLES` names."""
    found = untolerated_cycles(ROOT)
    assert not found, "import cycles: " + "; ".join(" <-> ".join(c) for c in found)


def test_a_planted_import_cycle_is_found(tmp_path):
    root = copy_of_the_library(tmp_path)
    path = root / "sim/cli/output.py"  # goal_run imports output; output now imports goal_run
    path.write_text(path.read_text() + "\n\ndef _late():\n    import sim.cli.goal_run\n")
    assert ["sim.cli.goal_run", "sim.cli.output"] in untolerated_cycles(root)


def test_the_floors_are_listed_once_each():
    prefixes = [prefix for _, floor in FLOORS for prefix in floor]
    assert len(prefixes) == len(set(prefixes))
    assert set(FACADES) <= set(library_modules(ROOT))


@pytest.mark.parametrize("module", ["wbc.core.errors", "wbc.model.kinematics", "tasks.com_task",
                                    "wbc.controller.whole_body_controller", "actions.go2",
                                    "actions.robot.control_loop", "sim.cli"])
def test_a_module_imports_first_in_a_fresh_interpreter(module):
    """Whatever a user imports first, the packages' facades and the floors load in an order
    that works (a facade loads the floors below it before its own)."""
    done = subprocess.run([sys.executable, "-c", f"import {module}"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr


def test_the_wbc_facade_types_and_loads_the_same_names():
    """``wbc`` loads its public names on first use from a table; the imports that type checkers
    read must name the same ones from the same modules."""
    import ast

    import wbc

    tree = ast.parse((ROOT / "wbc" / "__init__.py").read_text())
    typed = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING":
            for statement in node.body:
                assert isinstance(statement, ast.ImportFrom)
                typed.update({alias.name: statement.module for alias in statement.names})
    assert typed == wbc._HOMES
    assert sorted(wbc.__all__) == sorted(typed)
    for name in wbc.__all__:
        assert getattr(wbc, name) is not None


def test_tasks_and_wbc_import_in_either_order_without_a_fix():
    """The tasks' facade imports nothing from ``wbc`` to fix an order: importing a leaf of
    ``wbc`` does not load the controller."""
    source = (ROOT / "tasks" / "__init__.py").read_text()
    assert "import wbc\n" not in source and "import wbc  #" not in source
    probe = ("import sys, wbc.core.errors; "
             "assert 'wbc.controller.whole_body_controller' not in sys.modules; import tasks")
    done = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
