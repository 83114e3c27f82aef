"""``go2-wbc run --dds`` against the project's peers framed as Unitree's simulators
(``go2-wbc bridge --framing unitree-python|unitree-cpp``), three processes on a private DDS
domain (:mod:`benchmarks.unitree_peers`): with the default settings the controller says which
stream it recognised, stands the robot up from lying, and stand, high five (0.40 m, 2 s) and
sit SUCCEED. One run per peer here (about 40 s each); ``python -m benchmarks.unitree_peers
--runs 5`` repeats them (docs/dds.md has the figures).

In the slow stage (``make test-slow``): the quick stage covers the two framings without
processes (tests/test_dds_stream_kinds.py, test_state_framing.py, test_bringup_check.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from benchmarks.unitree_peers import run_peer
from sim.state_framing import UNITREE_CPP, UNITREE_PYTHON

pytestmark = pytest.mark.slow

#: What the controller must say first, and the staleness limit it derives [s].
RECOGNISED = {
    UNITREE_PYTHON: ("rt/lowstate: unitree-python (Unitree's Python simulator", 0.1),
    UNITREE_CPP: ("rt/lowstate: unitree-cpp (Unitree's C++ simulator", 0.04),
}
TARGET_M, HOLD_S = 0.40, 2.0
TILT_MAX_DEG, RAISED_RMS_MAX_MM = 3.0, 5.0


@pytest.mark.parametrize("framing", [UNITREE_PYTHON, UNITREE_CPP])
def test_run_dds_against_a_unitree_framed_peer_stands_high_fives_and_sits(
        framing: str, tmp_path: Path) -> None:
    result = run_peer(framing, tmp_path, domain_offset=3)
    print(f"\n{result.line()}")
    assert result.succeeded, result.line()
    recognised, limit_s = RECOGNISED[framing]
    start = "\n".join(result.start_lines)
    assert recognised in start and "foot_force absent" in start, start
    assert "foot contact from the schedule only" in start
    assert result.stale_after_s == pytest.approx(limit_s, rel=0.05)
    stream = result.robot["stream"]
    assert stream["kind"] == framing and stream["dropped"] == 0
    if framing == UNITREE_PYTHON:  # its frozen gaps repeat a state: told by the content
        assert stream["tick_counts"] is False and stream["repeats"] > 0
    else:
        assert stream["tick_counts"] is True
        assert result.joined["raised_foot_rms_mm"] < RAISED_RMS_MAX_MM
    # The truth: the front-right foot at the target for the hold, the body level.
    assert abs(result.foot_peak_m - TARGET_M) < 0.01
    assert result.foot_hold_s > 0.9 * HOLD_S
    assert result.tilt_max_deg < TILT_MAX_DEG
