"""The ``--viewer`` window for real, on a virtual screen (Xvfb, software OpenGL): it opens,
the run goes on while it draws, and the process exits cleanly when the run ends (before the
viewer's render loop was joined, the interpreter's exit terminated GLFW under it: a
segmentation fault, or a hang).

Skips, naming the package, where Xvfb is not installed (``scripts/setup.sh`` installs it).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Longest run of one command [s]: software rendering on 2 shared cores.
RUN_TIMEOUT_S = 240.0


@pytest.fixture(scope="module")
def display() -> Iterator[str]:
    """A virtual screen for this module's processes: its ``DISPLAY``."""
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        pytest.skip("Xvfb is not installed (Debian: apt-get install xvfb libgl1-mesa-dri; "
                    "scripts/setup.sh does it)")
    read_end, write_end = os.pipe()
    server = subprocess.Popen([xvfb, "-displayfd", str(write_end), "-screen", "0",
                               "1280x720x24", "-nolisten", "tcp"], pass_fds=(write_end,),
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_end)
    try:
        with os.fdopen(read_end) as told:
            number = told.readline().strip()  # written once the server accepts clients
        if not number:
            pytest.skip(f"Xvfb did not start (exit status {server.poll()})")
        yield f":{number}"
    finally:
        server.terminate()
        server.wait(timeout=30)


def go2_wbc(display: str, *args: str) -> subprocess.CompletedProcess[str]:
    env = os.environ | {"DISPLAY": display}
    env.pop("WAYLAND_DISPLAY", None)
    return subprocess.run([sys.executable, "-m", "sim.cli", *args], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)


def test_a_goal_with_the_window_open_exits_cleanly(display):
    done = go2_wbc(display, "stand", "--viewer", "--viewer-exit")
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "result: SUCCEEDED" in done.stdout
    assert "headless" not in done.stdout + done.stderr  # the window did open


# Slow (`make test-slow`): a second process on the window for 3 s of wall clock at 500 Hz; the
# quick stage opens the window for a goal (above).
@pytest.mark.slow
def test_the_bridge_with_the_window_open_keeps_its_rate_and_exits_cleanly(display, tmp_path):
    report = tmp_path / "bridge.json"
    done = go2_wbc(display, "bridge", "--domain", str(200 + os.getpid() % 30), "--viewer",
                   "--duration", "3", "--report", str(report))
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    assert "headless" not in done.stdout + done.stderr
    stats = json.loads(report.read_text())["stats"]
    assert stats["states_published"] >= 0.9 * 3 * 500  # drawing did not slow the physics
