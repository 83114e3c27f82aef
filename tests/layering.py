"""The library's floors, bottom first, and a reader of its imports that finds the upward ones.

A module may import modules of its own floor and of the floors below. The packages' facades
(``wbc/__init__.py``, ``tasks/__init__.py``, ``actions/__init__.py``, ...), which re-export
names for users, are not imported from inside the library: a module names the module it uses.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

#: ``(floor, module prefixes)``, bottom first; a module belongs to the floor of its longest
#: matching prefix.
FLOORS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("ground: errors, checks, conventions, compiled helpers", ("wbc.core",)),
    ("the model: description, kinematics, joint orders", ("wbc.model",)),
    ("the robot's records: motor command, sensor record, Unitree SDK", ("wbc.robot_io",)),
    ("QP backends", ("wbc.backends",)),
    ("tasks and constraints", ("tasks",)),
    ("state estimation", ("wbc.estimation",)),
    ("the controller", ("wbc.controller",)),
    ("motions", ("wbc.motions",)),
    ("the action framework", ("actions",)),
    ("the GO2's behaviours", ("actions.go2",)),
    ("the robot loop", ("actions.robot",)),
    ("the simulator", ("sim",)),
    ("the command line", ("sim.cli", "sim.action_cli", "sim.cli_trajectory_file")),
    ("benchmarks", ("benchmarks",)),
)
PACKAGES = ("wbc", "tasks", "actions", "sim", "benchmarks")
#: Package ``__init__`` modules that re-export names for users.
FACADES = ("wbc", "tasks", "actions", "wbc.backends")


@dataclass(frozen=True)
class Violation:
    module: str
    line: int
    imported: str
    why: str

    def __str__(self) -> str:
        return f"{self.module}:{self.line} imports {self.imported}: {self.why}"


def floor_of(module: str) -> int:
    """The index in :data:`FLOORS` of ``module``'s floor."""
    best, best_len = -1, -1
    for index, (_, prefixes) in enumerate(FLOORS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best_len:
                best, best_len = index, len(prefix)
    if best < 0:
        raise ValueError(f"{module}: on no floor; add its package to FLOORS")
    return best


def library_modules(root: Path) -> dict[str, Path]:
    """Every module of the library's packages under ``root``, by dotted name."""
    modules = {}
    for package in PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join(parts)] = path
    return modules


def imports_of(path: Path, modules: dict[str, Path]) -> list[tuple[int, str]]:
    """``(line, module)`` of every library module ``path`` imports, at any depth of its code
    (imports inside functions count: they are dependencies all the same)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            # `from package import module` imports the module; `from module import name`
            # imports the module.
            names = [f"{node.module}.{alias.name}" if f"{node.module}.{alias.name}" in modules
                     else node.module for alias in node.names]
        else:
            continue
        found += [(node.lineno, name) for name in names if name.split(".")[0] in PACKAGES]
    return found


def violations(root: Path) -> list[Violation]:
    """The imports under ``root`` that go up a floor or through a facade."""
    modules = library_modules(root)
    found: dict[tuple[str, int, str], Violation] = {}
    for module, path in modules.items():
        if module in FACADES or module in PACKAGES:
            continue  # the facades import what they re-export
        floor = floor_of(module)
        for line, imported in imports_of(path, modules):
            if imported in FACADES:
                why = "a facade for users; import the module that defines it"
            elif imported in modules and floor_of(imported) > floor:
                why = f"up from '{FLOORS[floor][0]}' to '{FLOORS[floor_of(imported)][0]}'"
            else:
                continue
            found[module, line, imported] = Violation(module, line, imported, why)
    return list(found.values())
