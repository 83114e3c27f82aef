"""The ``go2-wbc`` command line: an action client that drives a simulated GO2.

``main`` parses the command line (:mod:`sim.cli.parser`), turns the simulation's options into
an :class:`sim.episode.Episode` (:mod:`sim.cli.episode_options`) and runs the command: a goal
(:mod:`sim.cli.goal_commands`, :mod:`sim.cli.goal_run`), ``send-goal``, ``actions`` or
``interface`` (:mod:`sim.cli.send_goal`). Nothing here imports MuJoCo before a ``--video``
run has chosen its rendering backend.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

from sim.cli.dds_options import check_dds_options
from sim.cli.episode_options import check_options
from sim.cli.exit_codes import (
    EXIT_CODES_HELP,
    EXIT_INTERRUPTED,
    EXIT_NOT_SUCCEEDED,
    EXIT_REJECTED,
    EXIT_SUCCEEDED,
    EXIT_UNAVAILABLE,
    EXIT_USAGE,
)
from sim.cli.goal_run import GoalRun
from sim.cli.options import SETTLE_S
from sim.cli.output import state_line
from sim.cli.parser import build_parser
from sim.cli.send_goal import SendGoal
from sim.cli.trajectory_file import TRAJECTORY_FORMAT_HELP
from sim.episode_loop import startup_objects_frozen
from sim.kernel_cache import notice_if_cold

__all__ = [
    "EXIT_CODES_HELP", "EXIT_INTERRUPTED", "EXIT_NOT_SUCCEEDED", "EXIT_REJECTED",
    "EXIT_SUCCEEDED", "EXIT_UNAVAILABLE", "EXIT_USAGE", "SETTLE_S", "TRAJECTORY_FORMAT_HELP",
    "GoalRun", "SendGoal", "build_parser", "main", "startup_objects_frozen", "state_line",
]


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``go2-wbc``; returns the exit code (see ``go2-wbc --help``)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        if hasattr(args, "plant") and hasattr(args, "dds"):  # a goal command with --dds
            check_dds_options(args)
        if hasattr(args, "plant") and not getattr(args, "dds", False):  # they simulate
            check_options(args)
        if args.command == "run" or (hasattr(args, "plant") and not getattr(args, "dds", False)):
            notice_if_cold(sys.stderr)  # a first run compiles for a minute: say so first
        if getattr(args, "dds", False) and hasattr(args, "dds_run"):  # a goal over DDS
            return int(args.dds_run(args))
        return int(args.run(args))
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except RuntimeError as err:
        # MuJoCo refuses to import under a MUJOCO_GL it does not know: nothing can run.
        if "MUJOCO_GL" not in str(err):
            raise
        print(f"go2-wbc: {err}; unset it, or set one MuJoCo knows (egl, osmesa, glfw)",
              file=sys.stderr)
        return EXIT_UNAVAILABLE
