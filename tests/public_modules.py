"""The library's public modules, for the type check (tests/test_mypy_public.py,
``make typecheck``): the packages' facades, every module they import their names from, and
``sim.control_loop`` (the README's ``ControlLoop.simulated``).

Run as a script, it prints their paths (for ``mypy``'s command line).
"""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The packages' ``__init__`` files that re-export names for users.
FACADES = ("wbc", "tasks", "actions", "actions.robot", "wbc.backends")
#: Public modules outside the facades' imports.
ALSO_PUBLIC = ("sim.control_loop",)
LIBRARY = ("wbc", "tasks", "actions", "sim")


def module_path(module: str) -> Path:
    """The source file of a library module (a package's ``__init__.py``)."""
    base = ROOT.joinpath(*module.split("."))
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def public_modules() -> list[str]:
    """The facades, the library modules they import from (at any depth of their code,
    ``TYPE_CHECKING`` blocks included), the modules that define what they export (a name
    re-exported on its way) and :data:`ALSO_PUBLIC`, sorted."""
    found = set(FACADES) | set(ALSO_PUBLIC)
    for facade in FACADES:
        package = importlib.import_module(facade)
        for name in package.__all__:
            home = getattr(getattr(package, name), "__module__", None)
            if isinstance(home, str) and home.split(".")[0] in LIBRARY:
                found.add(home)
    for facade in FACADES:
        tree = ast.parse(module_path(facade).read_text())
        for node in ast.walk(tree):
            if (isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                    and node.module.split(".")[0] in LIBRARY):
                found.add(node.module)
        for node in ast.walk(tree):  # wbc's runtime table of homes: "wbc.x.y": (...)
            if isinstance(node, ast.Dict):
                found.update(key.value for key in node.keys
                             if isinstance(key, ast.Constant) and isinstance(key.value, str)
                             and key.value.split(".")[0] in LIBRARY)
    return sorted(module for module in found if module_path(module).is_file())


if __name__ == "__main__":
    print(" ".join(str(module_path(module).relative_to(ROOT)) for module in public_modules()))
