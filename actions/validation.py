"""Argument checks shared by the action modules."""

from __future__ import annotations

import math
import numbers
from typing import Any


def is_finite_real(value: Any) -> bool:
    """Whether ``value`` is a finite real number (``bool`` excluded; NumPy scalars included)."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
