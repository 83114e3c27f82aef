"""Shared fixtures: the GO2 description and model are loaded once per test session; on a fresh
clone, the estimators' numba kernels compile in a second process while the tests start."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from sim.video_recorder import choose_offscreen_gl
from wbc.model.description import Go2Description


def _offscreen_gl_in_this_process() -> None:
    """Choose MuJoCo's offscreen GL backend for this process only, before anything imports
    MuJoCo (which reads MUJOCO_GL once, at import): tests render frames here on machines
    without a display, while the command line run in subprocesses must still choose its own.
    """
    saved = {k: os.environ.get(k) for k in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    choose_offscreen_gl()
    import mujoco  # noqa: F401 - the import is what reads MUJOCO_GL

    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


# At conftest import, before any test module imports MuJoCo (none of the imports above does).
_offscreen_gl_in_this_process()

ROOT = Path(__file__).resolve().parents[1]
#: Run by a second process: both estimators' ticks on records of a GO2 at rest, which compiles
#: their kernels into numba's cache (the closed-loop tests' signatures: same types and layouts).
WARM_ESTIMATORS = """
from tests.synthetic_records import pose, run, started
from wbc import InvariantEkf, LinearKalmanFilter
for kind in (InvariantEkf, LinearKalmanFilter):
    run(started(kind), pose(), 3)
"""
_warmer: subprocess.Popen[bytes] | None = None
_warmer_errors = tempfile.TemporaryFile()  # the warm-up's stderr (a pipe could fill and block)


#: The quick stage's tests measured at 1 s or more, which run in the slow stage.
SLOW_STAGE_LIST = ROOT / "tests" / "slow_stage.txt"


def slow_stage_ids(path: Path = SLOW_STAGE_LIST) -> list[str]:
    """The node ids listed in ``tests/slow_stage.txt`` (a line: an id, then ``  # seconds``)."""
    lines = path.read_text().splitlines()
    return [line.rsplit("  # ", 1)[0].strip() for line in lines
            if line.strip() and not line.startswith("#")]


@pytest.hookimpl(tryfirst=True)  # before ``-m`` deselects by mark
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the listed tests slow, as their own ``@pytest.mark.slow`` would."""
    listed = set(slow_stage_ids())
    for item in items:
        if item.nodeid in listed:
            item.add_marker(pytest.mark.slow)


def pytest_sessionstart(session: pytest.Session) -> None:
    """On a fresh clone (no numba cache), compile the estimators' kernels in a second process.

    Compiling every kernel on first use costs about 77 s on one core; the first closed-loop test
    compiles the controller's (about half of it) first, and meanwhile the second core compiles
    the estimators', which that test then loads from the cache. With a cache, nothing starts.
    """
    global _warmer
    if (os.environ.get("NUMBA_DISABLE_JIT") == "1"
            or any((ROOT / "wbc" / "estimation" / "__pycache__").glob("*.nbi"))):
        return
    _warmer = subprocess.Popen([sys.executable, "-c", WARM_ESTIMATORS], cwd=ROOT,
                               stdout=subprocess.DEVNULL, stderr=_warmer_errors)


def pytest_sessionfinish(session: pytest.Session) -> None:
    """Stop the warm-up process if it still runs (a short selection of tests)."""
    if _warmer is not None and _warmer.poll() is None:
        _warmer.kill()
        _warmer.wait()


def pytest_terminal_summary(terminalreporter: pytest.TerminalReporter) -> None:
    """Say so when the warm-up failed: the tests compiled the kernels themselves (only slower)."""
    if _warmer is not None and _warmer.returncode not in (0, -9):
        _warmer_errors.seek(0)
        error = _warmer_errors.read().decode(errors="replace")
        terminalreporter.write_line(f"numba warm-up of the estimators failed (exit "
                                    f"{_warmer.returncode}): {error.strip()[-2000:]}")


@pytest.fixture(scope="session")
def description() -> Go2Description:
    return Go2Description()


@pytest.fixture(scope="session")
def model(description: Go2Description) -> pin.Model:
    return description.model


def random_configuration(model: pin.Model, rng: np.random.Generator, scale: float = 0.4,
                         base: np.ndarray | None = None) -> np.ndarray:
    """A configuration on the manifold: a standing pose moved by a random tangent vector."""
    q0 = Go2Description().pose("standing") if base is None else base
    dq = rng.uniform(-scale, scale, model.nv)
    q = pin.integrate(model, q0, dq)
    q[7:] = np.clip(q[7:], model.lowerPositionLimit[7:], model.upperPositionLimit[7:])
    return q
