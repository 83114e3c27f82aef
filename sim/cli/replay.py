"""``go2-wbc replay FILE``: a recorded run (``--mcap`` or ``--log``) in the MuJoCo viewer,
re-served live (``--foxglove``), or plotted (``--plot``)."""

from __future__ import annotations

import argparse
import sys
from typing import IO, Any

from sim.cli.arg_types import float_in, output_file
from sim.cli.exit_codes import EXIT_SUCCEEDED, EXIT_USAGE
from sim.cli.recording_options import DEFAULT_PORT
from wbc.core.errors import ConfigurationError

REPLAY_HELP = """\
examples:
  go2-wbc high-five --mcap hf.mcap; go2-wbc replay hf.mcap   # in the viewer (a display)
  go2-wbc replay hf.mcap --foxglove            # live on ws://127.0.0.1:8765
  go2-wbc replay hf.npz --plot hf.png          # a --log file, plotted afresh

"""


def add_replay_command(sub: Any) -> None:
    """The ``replay`` command."""
    from sim.cli.arg_types import whole_in

    replay = sub.add_parser(
        "replay", help="play a recorded run (--mcap or --log file) back: viewer, live, plot",
        description="Play a run recorded with --mcap (or a --log .npz) back: in the MuJoCo "
                    "viewer when a display exists, re-served live for Foxglove or Lichtblick "
                    "with --foxglove, plotted with --plot.",
        epilog=REPLAY_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    replay.add_argument("file", metavar="FILE", help="a .mcap recording or an .npz log")
    replay.add_argument("--foxglove", type=whole_in(0, 65535, what="a port"), nargs="?",
                        const=DEFAULT_PORT, metavar="PORT",
                        help=f"re-serve the run live on ws://127.0.0.1:PORT (default port "
                             f"{DEFAULT_PORT}; 0: any free port)")
    replay.add_argument("--plot", type=output_file(".png", ".pdf", ".svg"), metavar="FILE.png",
                        help="plot the run as the simulated commands' --plot does (a "
                             "simulated run's recording; default: no plot)")
    replay.add_argument("--headless", action="store_true",
                        help="no viewer even if a display exists (default: the viewer when a "
                             "display exists)")
    replay.add_argument("--speed", type=float_in(0.01, 100.0, what="a speed", unit="x",
                                                 fmt="g"), default=1.0, metavar="X",
                        help="played seconds per recorded second, in [0.01, 100] "
                             "(default: 1)")
    replay.set_defaults(run=replay_run, parser=replay)


def replay_run(args: argparse.Namespace, *, stream: IO[str] | None = None) -> int:
    """``go2-wbc replay``; returns the exit status."""
    from sim.recorded_run import RecordingError, load_run
    from sim.viewer import window_problem

    out = stream or sys.stdout

    def say(text: str) -> None:
        out.write(text + "\n")
        out.flush()

    try:
        run = load_run(args.file)
    except RecordingError as err:
        print(f"go2-wbc: replay: {err}", file=sys.stderr)
        return EXIT_USAGE
    say(run.describe())
    for note in run.notes:
        say(f"replay: note: {note}")
    if args.plot is not None:
        if not run.simulated:
            print(f"go2-wbc: replay: --plot: {run.path} holds no simulator truth (a robot's "
                  "run); the plot compares the estimate with the simulator's state",
                  file=sys.stderr)
            return EXIT_USAGE
        from sim.run_plot import write_plot

        title = run.metadata.get("command", "") or run.path.name
        write_plot(args.plot, run.arrays, title=f"{title} (replayed from {run.path.name})",
                   caption=run.caption())
        say(f"wrote {args.plot}")
    problem = "headless (--headless)" if args.headless else window_problem()
    if problem and args.foxglove is None:
        if args.plot is None:
            say(f"replay: no viewer: {problem}; --foxglove [PORT] serves the run live, "
                "--plot FILE.png plots it")
        return EXIT_SUCCEEDED
    return _play(args, run, say, viewer=not problem)


def _play(args: argparse.Namespace, run: Any, say: Any, *, viewer: bool) -> int:
    from sim.run_replay import RunReplay

    view = None
    if viewer:
        import mujoco.viewer

        from sim.simulator import Go2Simulator
        from sim.viewer import follow_base

        sim = Go2Simulator()
        handle = mujoco.viewer.launch_passive(sim.model, sim.data, show_left_ui=False,
                                              show_right_ui=False)
        with handle.lock():
            follow_base(handle.cam, sim.model)
        view = (handle, sim)
    replay = RunReplay(run, speed=args.speed)
    try:
        replay.play(view=view, port=args.foxglove,
                    on_serving=lambda port: say(f"foxglove: serving ws://127.0.0.1:{port}"))
    except ConfigurationError as err:
        print(f"go2-wbc: replay: {err}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        say(f"replay: interrupted after {replay.shown} states")
    finally:
        if view is not None:
            view[0].close()
    say(f"replayed {replay.shown} states over {run.duration_s:.3f} s"
        + (f", {replay.sent} messages served" if args.foxglove is not None else ""))
    return EXIT_SUCCEEDED
