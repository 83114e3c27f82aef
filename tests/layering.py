"""The library's floors, bottom first, and a reader of its imports that finds the upward ones
and the cycles.

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
    ("motions", ("wbc.motions", "wbc.locomotion")),
    ("the action framework", ("actions",)),
    ("ROS 2's standard interfaces", ("actions.ros_interfaces",)),
    ("the GO2's behaviours", ("actions.go2",)),
    ("the robot loop", ("actions.robot",)),
    ("the simulator", ("sim",)),
    ("ROS 2 (the ros2 extra: the one home of rclpy)", ("go2_ros2",)),
    ("the command line", ("sim.cli",)),
    ("benchmarks", ("benchmarks",)),
)
PACKAGES = ("wbc", "tasks", "actions", "sim", "benchmarks", "go2_ros2")
#: Package ``__init__`` modules that re-export names for users.
FACADES = ("wbc", "tasks", "actions", "actions.robot", "wbc.backends", "wbc.locomotion")
#: Packages inside which an import cycle is tolerated for now: the QP backend registry
#: (``wbc.backends.backend``) imports the backends it registers, which import it back.
TOLERATED_CYCLES = ("wbc.backends",)


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


def import_graph(root: Path) -> dict[str, set[str]]:
    """Every library module under ``root`` and the library modules it imports (at any depth
    of its code, ``TYPE_CHECKING`` blocks included)."""
    modules = library_modules(root)
    return {module: {name for _, name in imports_of(path, modules)
                     if name in modules and name != module}
            for module, path in modules.items()}


def import_cycles(root: Path) -> list[list[str]]:
    """The groups of library modules that import one another, directly or through others
    (the import graph's strongly connected components of two modules or more), each sorted,
    in the order found."""
    graph = import_graph(root)
    order: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles = []
    for start in graph:  # Tarjan's algorithm, with an explicit stack of iterators
        if start in order:
            continue
        order[start] = low[start] = len(order)
        stack.append(start)
        work = [(start, iter(sorted(graph[start])))]
        while work:
            module, successors = work[-1]
            successor = next(successors, None)
            if successor is not None:
                if successor not in order:
                    order[successor] = low[successor] = len(order)
                    stack.append(successor)
                    work.append((successor, iter(sorted(graph[successor]))))
                elif successor in stack:
                    low[module] = min(low[module], order[successor])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[module])
            if low[module] == order[module]:
                group = []
                while True:
                    member = stack.pop()
                    group.append(member)
                    if member == module:
                        break
                if len(group) > 1:
                    cycles.append(sorted(group))
    return cycles


def untolerated_cycles(root: Path) -> list[list[str]]:
    """:func:`import_cycles` less those inside one of :data:`TOLERATED_CYCLES`' packages."""
    def inside(cycle: list[str], package: str) -> bool:
        return all(m == package or m.startswith(package + ".") for m in cycle)

    return [cycle for cycle in import_cycles(root)
            if not any(inside(cycle, package) for package in TOLERATED_CYCLES)]
