"""The exit statuses of ``go2-wbc``, and the table its help shows."""

from __future__ import annotations

from sim.episode_result import REJECTED, UNAVAILABLE, EpisodeResult

#: The goal succeeded; it ended CANCELED or ABORTED; bad arguments; the server rejected the
#: goal; the command cannot run here; interrupted (Ctrl-C).
EXIT_SUCCEEDED, EXIT_NOT_SUCCEEDED, EXIT_USAGE, EXIT_REJECTED, EXIT_UNAVAILABLE = 0, 1, 2, 3, 4
EXIT_INTERRUPTED = 130

EXIT_CODES_HELP = """\
exit status:
    0  the goal SUCCEEDED
    1  the goal ended CANCELED or ABORTED (or did not end in time)
    2  bad arguments, an action that is not served included (the message names the
       argument and what is valid)
    3  the action server rejected the goal (the reason is printed)
    4  cannot run here (no offscreen rendering for --video, a MUJOCO_GL MuJoCo rejects)
  130  interrupted: Ctrl-C cancels the goal and waits for the robot to unwind
"""


def exit_code(result: EpisodeResult) -> int:
    """The exit status an episode's result gives."""
    if result.status == UNAVAILABLE:
        return EXIT_UNAVAILABLE
    if result.status == REJECTED:
        return EXIT_REJECTED
    if result.interrupted:
        return EXIT_INTERRUPTED
    return EXIT_SUCCEEDED if result.succeeded else EXIT_NOT_SUCCEEDED
