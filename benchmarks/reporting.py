"""What every benchmark report carries: the machine it ran on, and values JSON can hold."""

from __future__ import annotations

import importlib.metadata
import json
import os
import platform
import sys
import time
from collections.abc import Callable, Sequence
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


def run_and_report(run: Callable[[Callable[[str], None]], dict[str, Any]],
                   format_report: Callable[[dict[str, Any]], str], json_path: Path) -> int:
    """Run a benchmark, print its report and write it as JSON; the exit code (0).

    Args:
        run: The benchmark, given a log that prints each message on stderr with the seconds
            since the start; returns its report.
        format_report: The report as the text printed.
        json_path: Where the report is written (its directory made if needed); the report
            gains ``benchmark_wall_s``, the whole run's wall time [s].
    """
    started = time.perf_counter()
    report = run(lambda msg: print(f"[{time.perf_counter() - started:6.1f} s] {msg}",
                                   file=sys.stderr, flush=True))
    report["benchmark_wall_s"] = round(time.perf_counter() - started, 1)
    print(format_report(report))
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(json_safe(report), indent=1, allow_nan=False))
    print(f"\nWrote {json_path} in {report['benchmark_wall_s']:.1f} s")
    return 0
