"""Shared fixtures: the GO2 description and model are loaded once per test session."""

from __future__ import annotations

import os

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
