"""The README's pictures, made from this release by one command, with the numbers they show.

Run it with ``.venv/bin/python scripts/docs_media.py`` (the high five's pictures and plot:
about 10 s on 2 cores) or with ``--all`` (the benchmarks' plots too, running them: about 2
minutes more, 35 s for the QP timing and 85 s for the sweep). ``--only NAME`` (repeatable)
makes one of them:

- ``high-five``: ``docs/high_five.png`` (the foot held up) and ``docs/high_five.gif`` (the
  whole high five), the default overlays and their legend drawn. The camera is the video's
  view held still, so that the GIF's frames differ only where the robot and the overlays
  move, which keeps the file small.
- ``plot``: ``docs/high_five_plot.png``, by ``go2-wbc high-five --plot`` in a fresh process.
- ``qp``: ``docs/qp_timing.png``, by ``python -m benchmarks.qp_timing`` (full mode), or drawn
  from a report it wrote (``--qp-json FILE``) without running it again.
- ``sweep``: ``docs/sweep_plant_pushes.png``, by ``python -m benchmarks.sweep plant-pushes``
  (``--executor process``, every episode run again), or drawn from its results
  (``--sweep-results FILE``).

Each picture made is entered in ``docs/pictures.json``: its SHA-256, the command, the commit
and the numbers of the same run that the README quotes (the plot's tick times and tracking
error, the default backend's tick-time row, the sweep's outcome counts).
``tests/test_docs_pictures.py`` fails when a picture the README shows is missing from it or
differs from its entry, or when the README's numbers differ from its run's.
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image

from sim.episode import Episode
from sim.episode_result import EpisodeListener
from sim.episode_runner import EpisodeRunner
from sim.scene_overlay import SceneOverlay
from sim.video_recorder import VideoRecorder, choose_offscreen_gl

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: The pictures' record: file name -> sha256, command, commit, date, numbers.
MANIFEST = DOCS / "pictures.json"
#: What ``--only`` takes, and the files each makes.
PICTURES: dict[str, tuple[str, ...]] = {
    "high-five": ("high_five.png", "high_five.gif"),
    "plot": ("high_five_plot.png",),
    "qp": ("qp_timing.png",),
    "sweep": ("sweep_plant_pushes.png",),
}
#: Made without ``--all`` or ``--only``: the ones that run no benchmark.
DEFAULT_PICTURES = ("high-five", "plot")
#: Sim time [s] of the picture: the foot held up, its trace behind it (goal sent at 0.3 s).
PICTURE_S = 3.6
#: Camera distance [m] to the base (the video's is 1.6 m): the overlays read at 400 px.
DISTANCE_M = 1.25
#: The row of benchmarks.qp_timing's report that the README's table starts with.
QP_DEFAULT_ROW = "default (daqp)"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--all", action="store_true",
                        help="every picture, the benchmarks run for theirs (default: "
                             f"{', '.join(DEFAULT_PICTURES)})")
    parser.add_argument("--only", action="append", choices=tuple(PICTURES), default=[],
                        metavar="NAME",
                        help=f"make this picture, repeatable: {', '.join(PICTURES)} "
                             "(default: the ones --all does not need)")
    parser.add_argument("--qp-json", type=Path, metavar="FILE",
                        help="draw qp_timing.png from this report of benchmarks.qp_timing "
                             "instead of running it (default: run it)")
    parser.add_argument("--sweep-results", type=Path, metavar="FILE",
                        help="draw sweep_plant_pushes.png from these results of the "
                             "plant-pushes sweep instead of running it (default: run it)")
    parser.add_argument("--gif-fps", type=int, default=8, help="GIF frames per second "
                                                               "(default: 8)")
    parser.add_argument("--gif-width", type=int, default=400, help="GIF width [px] "
                                                                   "(default: 400)")
    parser.add_argument("--colours", type=int, default=192, help="GIF palette size "
                                                                 "(default: 192)")
    args = parser.parse_args(argv)
    if args.all and args.only:
        parser.error("--all and --only: choose one")
    names = tuple(PICTURES) if args.all else tuple(dict.fromkeys(args.only)) or DEFAULT_PICTURES
    if args.qp_json is not None and "qp" not in names:
        names += ("qp",)
    if args.sweep_results is not None and "sweep" not in names:
        names += ("sweep",)
    makers: dict[str, Callable[[], dict[str, dict[str, Any]]]] = {
        "high-five": lambda: make_high_five(args),
        "plot": make_plot,
        "qp": lambda: make_qp(args.qp_json),
        "sweep": lambda: make_sweep(args.sweep_results),
    }
    # The sim modules import MuJoCo only when they first simulate, and MuJoCo reads
    # MUJOCO_GL once, at import: choose before any maker runs (the plot's process inherits it).
    choose_offscreen_gl()
    manifest = json.loads(MANIFEST.read_text()) if MANIFEST.exists() else {}
    code = 0
    for name in names:
        started = time.perf_counter()
        entries = makers[name]()
        for file_name, entry in entries.items():
            code = max(code, entry.pop("exit_code", 0))
            path = DOCS / file_name
            manifest[file_name] = {"sha256": sha256(path), "bytes": path.stat().st_size,
                                   "commit": commit(), "date": str(datetime.date.today()),
                                   **entry}
            print(f"wrote docs/{file_name} ({path.stat().st_size / 1e3:.0f} kB): "
                  f"{readme_text(file_name, entry['numbers'])}")
        print(f"{name}: {time.perf_counter() - started:.0f} s")
        MANIFEST.write_text(json.dumps(dict(sorted(manifest.items())), indent=1) + "\n")
    return code


# ---------------------------------------------------------------------------- the pictures


def make_high_five(args: argparse.Namespace) -> dict[str, dict[str, Any]]:
    """docs/high_five.png and docs/high_five.gif, from one simulated high five."""
    shots = _Shots(args)
    runner = EpisodeRunner(Episode(), listener=shots, hooks=[shots])  # the default high five
    shots.status_of = lambda: (runner.phase, runner.progress)
    try:
        result = runner.run()
        for _ in range(args.gif_fps):  # a second on the end pose before the loop restarts
            shots.frames.append(shots.small.render(runner.loop))
    finally:
        shots.close()
    write_gif(DOCS / "high_five.gif", shots.frames, fps=args.gif_fps, colours=args.colours)
    command = "scripts/docs_media.py --only high-five"
    exit_code = 0 if result.status == "SUCCEEDED" else 1
    return {"high_five.png": {"made_by": command, "numbers": {"time_s": PICTURE_S},
                              "exit_code": exit_code},
            "high_five.gif": {"made_by": command, "numbers": {"frames": len(shots.frames),
                                                              "fps": args.gif_fps}}}


class _Shots(EpisodeListener):
    """The picture and the GIF's frames of a high five: cameras set up when the goal is sent
    (the robot settled), a frame every 1/fps s of sim time (a loop hook), the picture once."""

    def __init__(self, args: argparse.Namespace):
        self.fps, self.width = args.gif_fps, args.gif_width
        self.status_of: Any = None
        self.frames: list[np.ndarray] = []
        self.next_frame_s = 0.0
        self.picture_taken = False
        self.scratch = tempfile.TemporaryDirectory()  # the recorders' own MP4s are not kept
        self.recorders: list[VideoRecorder] = []

    def goal_sending(self, runner: EpisodeRunner, now_s: float) -> None:
        loop, folder = runner.loop, Path(self.scratch.name)
        overlay = SceneOverlay(status_of=self.status_of)
        self.picture = VideoRecorder(loop.sim, folder / "picture.mp4", fps=self.fps,
                                     size=(640, 480), overlay=overlay)
        self.small = VideoRecorder(loop.sim, folder / "gif.mp4", fps=self.fps,
                                   size=(self.width, self.width * 3 // 4), overlay=overlay)
        self.recorders = [self.picture, self.small]
        for camera in (self.picture.camera, self.small.camera):  # the video's view, held still
            lookat = loop.sim.data.xpos[camera.trackbodyid].copy()
            camera.type = 0  # mjCAMERA_FREE
            camera.lookat[:] = lookat
            camera.distance = DISTANCE_M
        self.next_frame_s = now_s

    def __call__(self, loop: Any, out: Any) -> None:
        now = loop.robot.time_s
        if now + 1e-9 >= self.next_frame_s:
            self.frames.append(self.small.render(loop))
            self.next_frame_s += 1.0 / self.fps
        if not self.picture_taken and now + 1e-9 >= PICTURE_S:
            Image.fromarray(self.picture.render(loop)).save(DOCS / "high_five.png",
                                                            optimize=True)
            self.picture_taken = True

    def close(self) -> None:
        for recorder in self.recorders:
            recorder.close()
        self.scratch.cleanup()


def make_plot() -> dict[str, dict[str, Any]]:
    """docs/high_five_plot.png by the command line in a fresh process, as a user runs it;
    its report gives the numbers (the same ticks as the plot's)."""
    with tempfile.TemporaryDirectory() as scratch:
        report_path = Path(scratch) / "report.json"
        argv = ["high-five", "--plot", str(DOCS / "high_five_plot.png"), "--report",
                str(report_path)]
        run([sys.executable, "-m", "sim.cli", *argv])
        metrics = json.loads(report_path.read_text())["metrics"]
    numbers = {"tick_median_us": round(metrics["tick_median_us"], 1),
               "tick_max_us": round(metrics["tick_max_us"], 1),
               "raised_foot_rms_mm": round(metrics["raised_foot_rms_mm"], 3)}
    return {"high_five_plot.png": {"made_by": "go2-wbc high-five --plot "
                                              "docs/high_five_plot.png --report FILE",
                                   "numbers": numbers}}


def make_qp(report_path: Path | None) -> dict[str, dict[str, Any]]:
    """docs/qp_timing.png: the benchmark run here, or its report drawn again."""
    from benchmarks.qp_timing import plot

    path = DOCS / "qp_timing.png"
    if report_path is None:
        with tempfile.TemporaryDirectory() as scratch:
            json_path = Path(scratch) / "qp_timing.json"
            run([sys.executable, "-m", "benchmarks.qp_timing", "--json", str(json_path),
                 "--plot", str(path)])
            report = json.loads(json_path.read_text())
        made_by = "python -m benchmarks.qp_timing --plot docs/qp_timing.png"
    else:
        report = json.loads(report_path.read_text())
        plot(report, path)
        made_by = f"python -m benchmarks.qp_timing --json {report_path}, drawn from that file"
    (row,) = [r for r in report["backends"] if r["name"] == QP_DEFAULT_ROW]
    numbers = {key: round(row[key], 1) for key in ("median_us", "p90_us", "p99_us")}
    return {"qp_timing.png": {"made_by": made_by, "numbers": {"mode": report["mode"],
                                                              **numbers}}}


def make_sweep(results_path: Path | None) -> dict[str, dict[str, Any]]:
    """docs/sweep_plant_pushes.png: the sweep run here (every episode), or its results drawn
    again."""
    from benchmarks.sweep_report import SweepReport
    from benchmarks.sweep_results import SweepResults
    from benchmarks.sweep_spec import SweepSpec

    path = DOCS / "sweep_plant_pushes.png"
    spec = SweepSpec.load("plant-pushes")
    if results_path is None:
        with tempfile.TemporaryDirectory() as scratch:
            fresh = Path(scratch) / "plant-pushes.jsonl"
            run([sys.executable, "-m", "benchmarks.sweep", "plant-pushes", "--executor",
                 "process", "--no-progress", "--results", str(fresh), "--plot", str(path)])
            report = SweepReport(spec, SweepResults(fresh).load())
        made_by = "python -m benchmarks.sweep plant-pushes --plot docs/sweep_plant_pushes.png"
    else:
        report = SweepReport(spec, SweepResults(results_path).load())
        report.write_heat_map(path)
        made_by = (f"python -m benchmarks.sweep plant-pushes --results {results_path}, "
                   "drawn from that file")
    counts = report.counts()
    numbers = {"episodes": len(report.rows), "succeeded": counts["S"],
               "aborted": counts["A"], "fell": counts["F"]}
    return {"sweep_plant_pushes.png": {"made_by": made_by, "numbers": numbers}}


def readme_text(file_name: str, numbers: dict[str, Any]) -> str:
    """Where the README quotes a picture's numbers, written as it should read."""
    if file_name == "high_five_plot.png":
        return (f"control tick {numbers['tick_median_us']:.0f} µs median and "
                f"{numbers['tick_max_us']:.0f} µs at most, the raised foot "
                f"{numbers['raised_foot_rms_mm']:.2f} mm RMS from its target")
    if file_name == "qp_timing.png":
        return (f"the default row's median, p90, p99: {numbers['median_us']:.0f}, "
                f"{numbers['p90_us']:.0f}, {numbers['p99_us']:.0f} µs")
    if file_name == "sweep_plant_pushes.png":
        return f"succeeded {numbers['succeeded']}/{numbers['episodes']}"
    return ", ".join(f"{k} {v}" for k, v in numbers.items())


# ---------------------------------------------------------------------------- helpers


def write_gif(path: Path, frames: list[np.ndarray], *, fps: int, colours: int) -> None:
    """An endless GIF of ``frames`` with one palette for all (no flicker between frames).

    The overlays cover few pixels, so a palette fitted to the frames as they are would
    spend itself on the greys of the floor and the robot: the saturated pixels are given
    as much weight as all the others.
    """
    sample = np.concatenate(frames[:: max(1, len(frames) // 8)], axis=0).reshape(-1, 3)
    spread = sample.max(axis=1).astype(int) - sample.min(axis=1)
    vivid = sample[spread > 80]
    if len(vivid):
        vivid = np.resize(vivid, (len(sample), 3))
        sample = np.concatenate([sample, vivid])
    side = int(np.ceil(np.sqrt(len(sample))))
    square = np.resize(sample, (side * side, 3)).reshape(side, side, 3).astype(np.uint8)
    palette = Image.fromarray(square).quantize(colours, method=Image.Quantize.MEDIANCUT)
    images = [Image.fromarray(f).quantize(palette=palette, dither=Image.Dither.NONE)
              for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=1000 // fps,
                   loop=0, optimize=True, disposal=1)


def run(command: list[str]) -> None:
    """Run a command from the repository's root, its output shown; stop if it fails."""
    print("$ " + " ".join(command[2:] if command[0] == sys.executable else command),
          flush=True)
    subprocess.run(command, cwd=ROOT, check=True)


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def commit() -> str:
    """The commit checked out, and whether files differ from it."""
    def git(*words: str) -> str:
        done = subprocess.run(["git", *words], cwd=ROOT, capture_output=True, text=True,
                              check=False)
        return done.stdout.strip()

    head = git("rev-parse", "--short", "HEAD") or "unknown"
    return head + (" with uncommitted changes" if git("status", "--porcelain") else "")


if __name__ == "__main__":
    sys.exit(main())
