"""The action packages' modules: no import cycle among them, none of over 400 lines."""

from __future__ import annotations

import itertools
from pathlib import Path

from tests.layering import imports_of, library_modules

ROOT = Path(__file__).resolve().parents[1]
#: Longest module of the action packages [lines]: a longer one is split by what it does.
MAX_LINES = 400


def action_import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the modules of ``actions`` (the facade aside) it imports, at any depth of its
    code and under ``TYPE_CHECKING`` too (a cycle there still ties the modules together)."""
    modules = library_modules(root)
    ours = {name for name in modules if name.startswith("actions.")}
    return {name: {imported for _, imported in imports_of(modules[name], modules)
                   if imported in ours and imported != name} for name in ours}


def cycle_in(graph: dict[str, set[str]]) -> list[str]:
    """One import cycle of ``graph`` as ``[a, b, ..., a]``, or ``[]`` if there is none."""
    state: dict[str, str] = {}  # "open" while on the path, "done" after
    path: list[str] = []

    def visit(name: str) -> list[str]:
        state[name] = "open"
        path.append(name)
        for imported in sorted(graph[name]):
            if state.get(imported) == "open":
                return [*path[path.index(imported):], imported]
            if imported not in state and (found := visit(imported)):
                return found
        state[name] = "done"
        path.pop()
        return []

    for name in sorted(graph):
        if name not in state and (found := visit(name)):
            return found
    return []


def test_the_action_modules_import_each_other_without_a_cycle():
    graph = action_import_graph(ROOT)
    assert {"actions.action_runner", "actions.client_goal_handle", "actions.errors"} <= set(graph)
    assert cycle_in(graph) == [], " -> ".join(cycle_in(graph))


def test_a_planted_cycle_is_found():
    graph = action_import_graph(ROOT)
    graph["actions.errors"].add("actions.client_goal_handle")  # as it was: a handle in an error
    found = cycle_in(graph)
    assert found[0] == found[-1]
    assert all(imported in graph[name] for name, imported in itertools.pairwise(found))
    assert {"actions.errors", "actions.client_goal_handle"} <= set(found)


def test_no_action_module_is_over_400_lines():
    lengths = {path.relative_to(ROOT).as_posix(): len(path.read_text().splitlines())
               for path in sorted((ROOT / "actions").rglob("*.py"))}
    assert len(lengths) > 30
    assert {path: n for path, n in lengths.items() if n > MAX_LINES} == {}
