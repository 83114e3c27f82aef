"""The quick and slow stages of a parametrized sweep (``make test`` and ``make test-slow``)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import pytest


def quick_first(values: Iterable[Any], quick: Callable[[Any], bool], *,
                unpack: bool = False) -> list[Any]:
    """A sweep's parameters: those ``quick`` picks run in the quick stage (``make test``, a
    representative of the sweep), the others carry the ``slow`` mark (``make test-slow``, which
    CI runs too). ``unpack``: each value is the tuple of several argument names' values."""
    return [value if quick(value) else
            pytest.param(*(value if unpack else (value,)), marks=pytest.mark.slow)
            for value in values]
