"""``--mcap FILE`` and ``--foxglove [PORT]``: a run's channels recorded to MCAP and served live
(:mod:`actions.robot.run_channels`), for the simulated commands and ``run --dds``.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from actions.robot.run_recording import DEFAULT_RATE_HZ, RunRecording
from sim.cli.arg_types import output_file, whole_in

if TYPE_CHECKING:
    from actions.robot.recording_process import RecordingProcess

#: The port ``--foxglove`` serves on when given without one (Foxglove's default).
DEFAULT_PORT = 8765


#: What a goal command's help says of them (its option list stays at 20 lines).
RECORDING_HELP = """\
recording (docs/recording.md):
  with --mcap FILE.mcap, the run is recorded for Foxglove or Lichtblick (transforms,
  joint states, targets, contact forces, plots, timing, the printed lines, the URDF);
  with --foxglove [PORT], the same channels are served live on ws://127.0.0.1:PORT
  (default 8765; 0: any free port), the run paced to the wall clock;
  go2-wbc replay FILE.mcap plays a recording back (viewer, --foxglove, --plot)

"""


def add_recording_options(group: Any, *, listed: bool = True) -> None:
    """``--mcap`` and ``--foxglove``, added to ``group``; ``listed=False``: left out of the
    option list (the goal commands' help says them in :data:`RECORDING_HELP`)."""
    def said(text: str) -> str:
        return text if listed else argparse.SUPPRESS

    group.add_argument("--mcap", type=output_file(".mcap"), metavar="FILE.mcap",
                       help=said("record the run in MCAP for Foxglove or Lichtblick: transforms, "
                            "joint states, targets and contact forces, plots, timing, the "
                            f"action's lines and the URDF, at {DEFAULT_RATE_HZ:g} Hz "
                            "(docs/recording.md; default: none)"))
    group.add_argument("--foxglove", type=whole_in(0, 65535, what="a port"), nargs="?",
                       const=DEFAULT_PORT, metavar="PORT",
                       help=said("serve the same channels live on ws://127.0.0.1:PORT for "
                            f"Foxglove or Lichtblick (default port {DEFAULT_PORT}; 0: any "
                            "free port; a simulated run is then paced to the wall clock; "
                            "default: off)"))


def open_recording(args: argparse.Namespace, *, control_period_s: float,
                   metadata: dict[str, str]) -> RunRecording | None:
    """The recording ``--mcap`` and ``--foxglove`` ask for (``None``: neither), logged in the
    simulated run's own hook.

    Raises:
        ConfigurationError: The port cannot be served.
    """
    mcap, port = getattr(args, "mcap", None), getattr(args, "foxglove", None)
    if mcap is None and port is None:
        return None
    from actions.robot.run_channels import RunChannels

    channels = RunChannels(mcap_path=mcap, port=port, metadata=metadata)
    return RunRecording(channels, control_period_s=control_period_s)


def open_recording_process(args: argparse.Namespace, *, control_period_s: float,
                           metadata: dict[str, str]) -> RecordingProcess | None:
    """The recording ``--mcap`` and ``--foxglove`` ask for (``None``: neither), built and
    written in a child process, off a wall-clock loop's thread (``run --dds``).

    Raises:
        ConfigurationError: The port cannot be served, or the child did not start.
    """
    mcap, port = getattr(args, "mcap", None), getattr(args, "foxglove", None)
    if mcap is None and port is None:
        return None
    from actions.robot.recording_process import RecordingProcess

    return RecordingProcess(mcap_path=mcap, port=port, metadata=metadata,
                            control_period_s=control_period_s)


def recording_summary(args: argparse.Namespace,
                      recording: RunRecording | RecordingProcess) -> str:
    """What the recording wrote or served, with its dropped snapshots."""
    where = []
    if getattr(args, "mcap", None) is not None:
        where.append(f"wrote {args.mcap}")
    if recording.port is not None:
        where.append(f"served ws://127.0.0.1:{recording.port}")
    from actions.robot.recording_process import RecordingProcess

    error = recording.error if isinstance(recording, RecordingProcess) else ""
    return (f"{' and '.join(where)} ({recording.logged} snapshots at "
            f"{recording.rate_hz:g} Hz, {recording.dropped} dropped)"
            + (f"; recording incomplete: {error}" if error else ""))
