"""Closed loop in MuJoCo at 1 kHz on the default (realistic) plant and the estimate: pushes of
5 N s (50 N for 0.1 s) in 8 directions at seeded random instants while trotting at 0.5 m/s."""

import numpy as np
import pytest

from sim.disturbances import Push
from tests.walking_loop import run_walk

pytestmark = pytest.mark.slow

SPACING_S = 1.2


def pushes() -> list[Push]:
    """One push every 1.2 s, at a random instant within its slot, the 8 directions in turn
    (relative to the heading: 0 from behind, 90 from the right, ...)."""
    rng = np.random.default_rng(31)
    return [Push(at_s=1.0 + SPACING_S * k + rng.uniform(0.0, 0.4), force_n=50.0,
                 duration_s=0.1, direction_deg=45.0 * k) for k in range(8)]


@pytest.fixture(scope="module")
def pushed():
    plan = pushes()
    return run_walk([(0.0, (0.5, 0.0, 0.0))], plan[-1].at_s + 1.2, pushes=plan), plan


def test_eight_pushes_of_5_ns_while_trotting_no_fall(pushed):
    run, plan = pushed
    assert all(p.impulse_ns == pytest.approx(5.0) for p in plan)
    assert not run.fell
    assert run.failures == 0
    applied = run.loop.hooks[-1].applied
    assert len(applied) == 8
    # Still walking at the command after the last push.
    forward_mps, _, _ = run.mean_velocity(plan[-1].at_s + 0.2, run.times[-1])
    assert forward_mps == pytest.approx(0.5, abs=0.15)
