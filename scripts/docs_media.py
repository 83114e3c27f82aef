"""The README's picture and animation: the default high five with every default overlay.

Run it with ``.venv/bin/python scripts/docs_media.py`` (about a minute on software GL); it
writes ``docs/high_five.png`` (the foot held up) and ``docs/high_five.gif`` (the whole high
five). The camera is the video's view held still, so that the GIF's frames differ only
where the robot and the overlays move, which keeps the file small.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from sim.video_recorder import choose_offscreen_gl

choose_offscreen_gl()  # before MuJoCo is imported

import numpy as np
from PIL import Image

from actions import GoalStatus, HighFiveGoal
from sim.control_loop import ControlLoop
from sim.scene_overlay import SceneOverlay
from sim.video_recorder import VideoRecorder

DOCS = Path(__file__).resolve().parents[1] / "docs"
#: Sim time [s] of the picture: the foot held up, its trace behind it (goal sent at 0.3 s).
PICTURE_S = 3.6
#: Camera distance [m] to the base (the video's is 1.6 m): the overlays read at 400 px.
DISTANCE_M = 1.25


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--gif-fps", type=int, default=8, help="GIF frames per second")
    parser.add_argument("--gif-width", type=int, default=400, help="GIF width [px]")
    parser.add_argument("--colours", type=int, default=192, help="GIF palette size")
    args = parser.parse_args(argv)

    loop = ControlLoop.simulated()
    loop.spin_for(0.3)  # settle, as the command line does
    status = {"phase": "", "progress": 0.0}
    done: list[GoalStatus] = []

    def on_feedback(message) -> None:
        status["phase"], status["progress"] = message.feedback.phase, message.feedback.progress

    future = loop.client("high_five").send_goal_async(
        HighFiveGoal(target_height=0.40, hold_seconds=2), feedback_callback=on_feedback)
    future.add_done_callback(lambda f: f.result().get_result_async().add_done_callback(
        lambda r: done.append(r.result().status)))
    overlay = SceneOverlay(status_of=lambda: (status["phase"], status["progress"]))
    width = args.gif_width
    scratch = tempfile.TemporaryDirectory()  # the recorders' own MP4s are not kept
    folder = Path(scratch.name)
    recorder = VideoRecorder(loop.sim, folder / "picture.mp4", fps=args.gif_fps,
                             size=(640, 480), overlay=overlay)
    small = VideoRecorder(loop.sim, folder / "gif.mp4", fps=args.gif_fps,
                          size=(width, width * 3 // 4), overlay=overlay)
    for camera in (recorder.camera, small.camera):  # the video's view, nearer, held still
        lookat = loop.sim.data.xpos[camera.trackbodyid].copy()
        camera.type = 0  # mjCAMERA_FREE
        camera.lookat[:] = lookat
        camera.distance = DISTANCE_M
    frames: list[np.ndarray] = []
    next_frame_s = loop.robot.time_s
    picture_taken = False
    try:
        while not done:
            loop.spin_once()
            now = loop.robot.time_s
            if now + 1e-9 >= next_frame_s:
                frames.append(small.render(loop))
                next_frame_s += 1.0 / args.gif_fps
            if not picture_taken and now + 1e-9 >= PICTURE_S:
                Image.fromarray(recorder.render(loop)).save(DOCS / "high_five.png",
                                                            optimize=True)
                picture_taken = True
        for _ in range(args.gif_fps):  # a second on the end pose before the loop restarts
            frames.append(small.render(loop))
    finally:
        recorder.close()
        small.close()
        scratch.cleanup()
    write_gif(DOCS / "high_five.gif", frames, fps=args.gif_fps, colours=args.colours)
    for name in ("high_five.png", "high_five.gif"):
        print(f"wrote docs/{name} ({(DOCS / name).stat().st_size / 1e3:.0f} kB)")
    return 0 if done[0] == GoalStatus.SUCCEEDED else 1


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


if __name__ == "__main__":
    sys.exit(main())
