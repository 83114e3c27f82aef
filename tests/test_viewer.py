"""The viewer hook's window lifecycle, on a scripted viewer handle: closed or destroyed mid-run,
held open on the final state, closed at the end; and the command line's --viewer around it."""

from __future__ import annotations

import contextlib
import io
import re
import time
import types
from collections.abc import Callable

import mujoco
import pytest

import sim.viewer
from sim import episode_runner
from sim.cli import EXIT_SUCCEEDED, main
from sim.control_loop import ControlLoop
from sim.scene_overlay import DEFAULT_OVERLAYS, SceneOverlay
from sim.viewer import HOLD_NOTE, ViewerHook

GRID = mujoco.mjtGridPos


class ScriptedHandle:
    """What the hook uses of MuJoCo's passive viewer handle, recorded; its window stays open
    while ``open_while(handle)`` says so, and ``fail`` names a call that raises, as calls on
    a destroyed window can."""

    def __init__(self, model: mujoco.MjModel, *,
                 open_while: Callable[[ScriptedHandle], bool] = lambda handle: True,
                 fail: str = ""):
        self.cam = mujoco.MjvCamera()
        self.user_scn = mujoco.MjvScene(model, maxgeom=2000)
        self.open_while = open_while
        self.fail = fail
        self.failing = False  # set by the test: from now on, `fail` raises
        self.texts: list = []
        self.syncs = 0
        self.closed = False
        self.hold_polls = 0  # counted by the tests' sleep

    def _maybe_fail(self, call: str) -> None:
        if self.failing and call == self.fail:
            raise RuntimeError(f"{call}: the GLFW window was destroyed")

    def lock(self):
        self._maybe_fail("lock")
        return contextlib.nullcontext()

    def is_running(self) -> bool:
        self._maybe_fail("is_running")
        return not self.closed and self.open_while(self)

    def sync(self) -> None:
        self._maybe_fail("sync")
        self.syncs += 1

    def set_texts(self, texts) -> None:
        self._maybe_fail("set_texts")
        self.texts.append(texts)

    def close(self) -> None:
        self.closed = True
        self._maybe_fail("close")


@pytest.fixture(scope="module")
def loop() -> ControlLoop:
    return ControlLoop.simulated()


def spin_with(loop: ControlLoop, hook: ViewerHook, seconds: float) -> None:
    """Spin ``loop`` for ``seconds`` with ``hook`` called every tick, as the CLI does."""
    loop.hooks.append(hook)
    try:
        loop.spin_for(seconds)
    finally:
        loop.hooks.remove(hook)


# ----------------------------------------------------------------------------- the hook


def test_a_window_closed_mid_run_is_reported_once_and_left_alone(loop):
    close_at_s = loop.sim.time_s + 0.2
    handle = ScriptedHandle(loop.sim.model,
                            open_while=lambda h: loop.sim.time_s < close_at_s)
    reports: list[float] = []
    hook = ViewerHook(loop.sim, overlay=SceneOverlay(), handle=handle,
                      on_closed=lambda: reports.append(hook.closed_at_s))
    spin_with(loop, hook, 0.5)
    assert len(reports) == 1 and hook.error is None
    # Noticed at the first sync (60 a simulated second) after it closed.
    assert close_at_s <= reports[0] < close_at_s + 1 / 60 + 1e-6
    assert 11 <= handle.syncs <= 13 and not hook.is_open
    syncs = handle.syncs
    spin_with(loop, hook, 0.1)  # nothing more: no sync, no second report
    assert handle.syncs == syncs and len(reports) == 1
    assert hook.hold(loop, sleep=pytest.fail) is False
    hook.close()
    hook.close()
    assert handle.closed


@pytest.mark.parametrize("call", ["sync", "lock", "is_running", "set_texts"])
def test_a_destroyed_window_never_raises(loop, call):
    handle = ScriptedHandle(loop.sim.model, fail=call)
    reports: list[str] = []
    hook = ViewerHook(loop.sim, overlay=SceneOverlay(), handle=handle,
                      on_closed=lambda: reports.append(str(hook.error)))
    spin_with(loop, hook, 0.05)
    assert handle.syncs >= 3 and not reports
    handle.failing = True
    spin_with(loop, hook, 0.1)
    if call == "set_texts":  # raised in the text thread, which ends; the loop's reports it
        hook._texter.join(timeout=5.0)
        spin_with(loop, hook, 0.05)
    expected = [] if call == "is_running" else [f"{call}: the GLFW window was destroyed"]
    # A failing is_running reads as a closed window; the others are the error reported.
    assert reports == (expected or ["None"]), reports
    assert hook.closed_at_s is not None and not hook.is_open
    assert hook.hold(loop, sleep=pytest.fail) is False
    hook.close()


def test_close_never_raises_even_when_the_handle_does(loop):
    handle = ScriptedHandle(loop.sim.model, fail="close")
    hook = ViewerHook(loop.sim, overlay=SceneOverlay(), handle=handle)
    handle.failing = True
    hook.close()
    assert handle.closed


def test_hold_shows_the_final_state_paused_until_the_window_is_closed(loop):
    handle = ScriptedHandle(loop.sim.model, open_while=lambda h: h.hold_polls < 3)
    overlay = SceneOverlay(DEFAULT_OVERLAYS)
    hook = ViewerHook(loop.sim, overlay=overlay, handle=handle)
    spin_with(loop, hook, 0.1)
    now_s, syncs = loop.sim.time_s, handle.syncs
    waits: list[float] = []

    def sleep(seconds: float) -> None:
        waits.append(seconds)
        handle.hold_polls += 1

    assert hook.hold(loop, sleep=sleep) is True
    assert waits == [0.1, 0.1, 0.1]
    assert loop.sim.time_s == now_s  # paused: the state the run ended in
    assert handle.syncs == syncs + 1  # that state, with its overlay, once
    hook.close()
    panel, legend, note = handle.texts[-1]
    assert panel == (None, GRID.mjGRID_TOPLEFT, *overlay.status_lines(loop))
    assert legend == (None, GRID.mjGRID_BOTTOMLEFT, *overlay.legend_lines())
    assert note == (None, GRID.mjGRID_TOPRIGHT, *HOLD_NOTE.split("\t"))
    assert note[2:] == ("paused", "the final state: close the window to exit")
    assert hook.hold(loop, sleep=pytest.fail) is False  # closed: nothing to hold


def test_without_an_overlay_the_hold_still_says_it_is_paused(loop):
    handle = ScriptedHandle(loop.sim.model, open_while=lambda h: h.hold_polls < 1)
    hook = ViewerHook(loop.sim, handle=handle)
    spin_with(loop, hook, 0.05)
    assert handle.user_scn.ngeom == 0

    def sleep(seconds: float) -> None:
        handle.hold_polls += 1

    assert hook.hold(loop, sleep=sleep) is True
    hook.close()
    assert handle.texts == [[(None, GRID.mjGRID_TOPRIGHT, *HOLD_NOTE.split("\t"))]]


# ----------------------------------------------------------------------------- --viewer


class ViewerRun:
    """``go2-wbc`` run in this process with a scripted window (no display needed): the
    hook's handle is a :class:`ScriptedHandle`; ``time.sleep`` (the pacing, the hold's
    polls) only records its calls, with the sim time, and the viewer's wall clock advances
    only by those sleeps (so the pacing's sleeps do not depend on the machine's speed)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, **handle_options):
        self.handle: ScriptedHandle | None = None
        self.hook: ViewerHook | None = None
        self.sleeps: list[tuple[float, float]] = []  # (sim time [s], seconds)

        def make_hook(sim, **options):
            self.handle = ScriptedHandle(sim.model, **handle_options)
            self.hook = ViewerHook(sim, handle=self.handle, **options)
            return self.hook

        wall_s = [0.0]

        def viewer_sleep(seconds: float) -> None:
            wall_s[0] += seconds
            time.sleep(seconds)  # the recorder below, or a test's own

        def sleep(seconds: float) -> None:
            self.sleeps.append((self.hook.sim.time_s, seconds))
            if seconds == 0.1:  # the hold's poll (the pacing's never is exactly)
                self.handle.hold_polls += 1

        monkeypatch.setattr(episode_runner, "window_problem", lambda: "")
        monkeypatch.setattr(episode_runner, "ViewerHook", make_hook)
        monkeypatch.setattr(time, "sleep", sleep)
        monkeypatch.setattr(sim.viewer, "time",
                            types.SimpleNamespace(sleep=viewer_sleep,
                                                  perf_counter=lambda: wall_s[0]))

    def __call__(self, *options: str) -> tuple[int, list[str]]:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = main(["high-five", "--hold", "0", "--viewer", *options])
        return code, out.getvalue().splitlines()


def result_time(lines: list[str]) -> float:
    (line,) = [line for line in lines if "result: SUCCEEDED" in line]
    return float(re.match(r"\[\s*([\d.]+) s\]", line).group(1))


def test_the_viewer_stays_open_on_the_final_state_until_its_window_is_closed(monkeypatch):
    run = ViewerRun(monkeypatch, open_while=lambda h: h.hold_polls < 3)
    code, lines = run()
    assert code == EXIT_SUCCEEDED
    end_s = result_time(lines)
    assert lines[-1] == (f"[{end_s:7.3f} s] viewer: paused on the final state; close the "
                         "window to exit (--viewer-exit closes it at the end)")
    polls = [(t, s) for t, s in run.sleeps if s == 0.1]
    assert [s for _, s in polls] == [0.1] * 3
    # Paused: no tick while it waits (the sim's clock is one step past the result's tick).
    assert {t for t, _ in polls} == {run.hook.sim.time_s}
    assert run.hook.sim.time_s == pytest.approx(end_s + 1e-3, abs=1e-6)
    assert len(run.sleeps) > 100  # --viewer paces the run to the wall clock
    assert run.handle.closed and not any("the window was closed" in line for line in lines)


def test_ctrl_c_while_the_viewer_holds_closes_it(monkeypatch):
    run = ViewerRun(monkeypatch)

    def interrupt(seconds: float) -> None:
        if seconds == 0.1:
            raise KeyboardInterrupt

    monkeypatch.setattr(time, "sleep", interrupt)
    code, lines = run()
    assert code == EXIT_SUCCEEDED and "viewer: paused on the final state" in lines[-1]
    assert run.handle.closed


def test_viewer_exit_closes_the_window_when_the_goal_ends(monkeypatch):
    run = ViewerRun(monkeypatch, open_while=lambda h: pytest.fail("held") if h.hold_polls
                    else True)
    code, lines = run("--viewer-exit")
    assert code == EXIT_SUCCEEDED
    assert "result: SUCCEEDED" in lines[-1] and not any("viewer:" in line for line in lines)
    assert not [s for s in run.sleeps if s[1] == 0.1] and run.handle.closed


def test_a_window_closed_mid_run_is_said_and_the_run_goes_on_unpaced(monkeypatch):
    run = ViewerRun(monkeypatch, open_while=lambda h: run.hook.sim.time_s < 1.0)
    code, lines = run()
    assert code == EXIT_SUCCEEDED and "result: SUCCEEDED" in lines[-1]
    (line,) = [line for line in lines if "viewer:" in line]
    closed_s = float(re.match(r"\[\s*([\d.]+) s\]", line).group(1))
    assert line == (f"[{closed_s:7.3f} s] viewer: the window was closed; the run goes on "
                    "headless, as fast as possible")
    assert 1.0 <= closed_s < 1.0 + 1 / 60 + 2e-3
    assert lines.index(line) < len(lines) - 1  # said when it happened, among the feedback
    assert run.sleeps and max(t for t, _ in run.sleeps) <= closed_s + 1e-3  # no more pacing


def test_realtime_keeps_the_pace_after_the_window_is_closed(monkeypatch):
    run = ViewerRun(monkeypatch, open_while=lambda h: run.hook.sim.time_s < 1.0)
    code, lines = run("--realtime")
    assert code == EXIT_SUCCEEDED
    assert any(line.endswith("viewer: the window was closed; the run goes on headless")
               for line in lines)
    assert max(t for t, _ in run.sleeps) > 5.0


def test_a_destroyed_window_mid_run_is_said_and_never_raises(monkeypatch):
    run = ViewerRun(monkeypatch, fail="sync")

    def sleep(seconds: float) -> None:  # destroyed at 1 s of sim time
        run.handle.failing = run.hook.sim.time_s >= 1.0

    monkeypatch.setattr(time, "sleep", sleep)
    code, lines = run()
    assert code == EXIT_SUCCEEDED and "result: SUCCEEDED" in lines[-1]
    (line,) = [line for line in lines if "viewer:" in line]
    assert line.endswith("viewer: the window failed (RuntimeError: sync: the GLFW window was "
                         "destroyed); the run goes on headless, as fast as possible")
