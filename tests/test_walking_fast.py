"""Closed loop in MuJoCo on the default (realistic) plant and the estimate: 1.0 m/s at 1 kHz,
and 0.5 m/s at the GO2's usual 500 Hz; measured on the simulator's truth."""

import numpy as np
import pytest

from tests.walking_loop import run_walk

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def one_mps():
    return run_walk([(0.0, (1.0, 0.0, 0.0))], 6.5, stop_at_s=5.0)


@pytest.fixture(scope="module")
def at_500_hz():
    return run_walk([(0.0, (0.5, 0.0, 0.0))], 6.5, stop_at_s=5.0, control_period_s=2e-3)


def test_one_metre_per_second_without_falling(one_mps):
    assert not one_mps.fell
    forward_mps, _, _ = one_mps.mean_velocity(1.0, 5.0)
    assert forward_mps == pytest.approx(1.0, rel=0.10)
    assert one_mps.done_s is not None and one_mps.done_s - one_mps.stop_s <= 1.0


def test_half_metre_per_second_at_500_hz(at_500_hz):
    assert not at_500_hz.fell and at_500_hz.failures == 0
    forward_mps, lateral_mps, _ = at_500_hz.mean_velocity(0.5, 5.0)
    assert forward_mps == pytest.approx(0.5, rel=0.10)
    assert abs(lateral_mps) < 0.05
    assert at_500_hz.done_s is not None and at_500_hz.done_s - at_500_hz.stop_s <= 1.0
    base = np.asarray(at_500_hz.base)
    assert abs(base[at_500_hz.window(1.0, 5.0), 2].mean() - base[0, 2]) < 0.01
