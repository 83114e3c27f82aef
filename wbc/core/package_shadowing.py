"""The check that a user's own module does not shadow one of the library's top-level packages.

The library's packages have generic names (``tasks``, ``sim``, ``actions``, ``benchmarks``): a
user's ``tasks.py`` next to their script comes first on ``sys.path`` and breaks the library with
an unrelated ImportError (``'tasks' is not a package``). Each package's ``__init__`` calls
:func:`check_not_shadowed` so the first import of the library names the file to rename instead.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from wbc.core.errors import WbcError

#: The library's top-level packages, all installed side by side (a wheel or a checkout).
PACKAGES = ("wbc", "tasks", "actions", "sim", "benchmarks")
#: The directory that holds them: this file is ``<root>/wbc/core/package_shadowing.py``.
_ROOT = Path(__file__).resolve().parents[2]


class PackageShadowedError(WbcError, ImportError):
    """A module of the user's comes first on ``sys.path`` under a library package's name."""


def _origin(name: str) -> str | None:
    """Where ``import name`` takes (or took) the top-level module ``name`` from; None when it
    would find nothing."""
    module = sys.modules.get(name)
    if module is not None:
        return getattr(module, "__file__", None) or repr(module)
    try:
        spec = importlib.util.find_spec(name)  # finds, never executes the module
    except (ImportError, ValueError):
        return None
    if spec is None:
        return None
    return spec.origin or ", ".join(spec.submodule_search_locations or ()) or name


def check_not_shadowed(packages: tuple[str, ...] = PACKAGES) -> None:
    """Raise when one of ``packages`` would be (or was) imported from anywhere but the
    library's own directory.

    Raises:
        PackageShadowedError: one line naming the file that shadows the package and saying to
            rename it.
    """
    for name in packages:
        origin = _origin(name)
        expected = _ROOT / name / "__init__.py"
        if origin is None or Path(origin).resolve() == expected:
            continue
        raise PackageShadowedError(
            f"{origin} shadows the go2-wbc package '{name}' (it comes first on sys.path, "
            f"so 'import {name}' finds it instead of {expected.parent}); rename that file "
            f"or directory (e.g. my_{name}.py)")
