"""What every benchmark report carries: the machine it ran on, and values JSON can hold."""

from __future__ import annotations

import importlib.metadata
import os
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

#: The packages whose versions a report lists unless it names its own.
PACKAGES = ("pin", "placo", "mujoco", "daqp", "osqp", "qpsolvers", "numpy", "proxsuite", "piqp",
            "quadprog")


def machine(packages: Sequence[str] = PACKAGES, *, with_platform: bool = True
            ) -> dict[str, Any]:
    """CPU, cores, load, Python (the platform with ``with_platform``) and the versions of
    ``packages`` (``None`` for one that is not installed)."""
    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {}
    for package in packages:
        try:
            versions[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            versions[package] = None
    info: dict[str, Any] = {"cpu": cpu, "cores": os.cpu_count(),
                            "python": platform.python_version(),
                            "load_average_1_5_15_min": list(os.getloadavg())}
    if with_platform:
        info["platform"] = platform.platform()
    return {**info, "versions": versions}


def json_safe(value: Any) -> Any:
    """``value`` with NumPy scalars made plain and non-finite numbers ``None`` (JSON has no
    NaN or infinity), in nested dicts, lists and tuples."""
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, np.integer | np.bool_):
        return value.item()
    return value
