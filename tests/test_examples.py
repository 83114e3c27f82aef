"""The examples and scripts run and do what their docstrings say.

``examples/custom_task.py`` has its own test, ``tests/test_custom_task.py``.
"""

from __future__ import annotations

import runpy
from pathlib import Path

import pytest

from actions import GoalStatus

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def example(name: str) -> dict:
    """The example's module namespace, its ``__main__`` block not run."""
    return runpy.run_path(str(EXAMPLES / f"{name}.py"), run_name=f"examples.{name}")


def test_own_loop_raises_the_foot_and_puts_it_back():
    summary = example("own_loop")["run"](height_m=0.30, hold_s=0.5)
    # The stand-in robot moves exactly as planned, so the foot reaches the target (its
    # centre, 0.30 m) and every tick's QP is solved.
    assert summary["highest_m"] == pytest.approx(0.30, abs=2e-3)
    assert summary["not_ok"] == 0
    assert 5000 < summary["ticks"] < 8000


def test_own_plant_runs_the_high_five_on_a_plant_built_from_the_urdf():
    status, message, highest = example("own_plant")["run"](height_m=0.35, hold_seconds=1)
    assert status is GoalStatus.STATUS_SUCCEEDED, message
    assert "back on four feet" in message
    # Measured by the plant itself (its foot is the calf's mesh, not the model's sphere):
    # the target is the sphere centre's height, so the mesh point sits within a few mm.
    assert highest == pytest.approx(0.35, abs=0.01)


def test_the_examples_main_blocks_print_their_results(capsys):
    runpy.run_path(str(EXAMPLES / "own_loop.py"), run_name="__main__")
    assert "ticks not OK: 0" in capsys.readouterr().out


def test_the_tutorial_style_script_runs_its_high_five(capsys):
    script = runpy.run_path(str(EXAMPLES.parent / "scripts" / "high_five.py"),
                            run_name="scripts.high_five")
    assert script["main"]() == 0
    out = capsys.readouterr().out
    assert "Goal accepted" in out and "Feedback: ready" in out
    assert "Result: SUCCEEDED: high five done" in out
