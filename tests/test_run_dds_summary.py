"""``go2-wbc run --dds``'s exit summary says what happened: how the stop ended (a sit that did
not succeed is named, never "at rest") and every change of the loop's mode."""

from __future__ import annotations

from sim.cli.run_dds import _summary

STAGES = ("read", "actions", "controller", "write", "bridge", "hooks", "gc", "tick", "cpu",
          "latency", "wake")


def report(notes: list[str], modes: list[dict]) -> dict:
    return {"series": {name: {"mean_ms": 0.1, "p99_ms": 0.2} for name in STAGES},
            "robot": {}, "stop": {"reason": "SIGINT", "notes": notes}, "duration_s": 9.0,
            "ticks": 4500, "rate_hz": 500.0, "deadline_misses": 0, "no_fresh_state_ticks": 500,
            "watchdog_trips": 1, "modes": modes}


def test_the_summary_names_the_modes_and_an_aborted_sit():
    text = _summary(report(
        ["sit ended ABORTED: aborted: controller fault (...)",
         "damping (not at rest: base at 0.30 m)"],
        [{"t_s": 0.0, "mode": "CONTROLLING", "reason": ""},
         {"t_s": 3.21, "mode": "FALLBACK", "reason": "watchdog: no fresh robot state for 41 ms"},
         {"t_s": 4.2, "mode": "RECOVERING", "reason": "trustworthy state back"},
         {"t_s": 6.2, "mode": "CONTROLLING", "reason": ""}]))
    assert text.startswith("stopped (SIGINT; sit ended ABORTED: aborted: controller fault (...); "
                           "damping (not at rest: base at 0.30 m)) after 9.0 s")
    assert "at rest)" not in text.replace("not at rest", "")
    assert text.endswith("\n  loop modes:\n  3.21 s: FALLBACK (watchdog: no fresh robot state for "
                         "41 ms)\n  4.20 s: RECOVERING (trustworthy state back)\n  6.20 s: "
                         "CONTROLLING")
    # A run that never lost its state says nothing of modes.
    assert "loop modes" not in _summary(report([], [{"t_s": 0.0, "mode": "CONTROLLING",
                                                     "reason": ""}]))
