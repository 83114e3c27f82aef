"""A sweep's results in JSON Lines: one episode a line, appended as it ends, read to resume."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from wbc.core.errors import WbcError


class SweepResultsError(WbcError, ValueError):
    """A results file that cannot be read back (a damaged line before the last)."""


class SweepResults:
    """The results file of a sweep.

    Each line is one record: ``key`` (:attr:`benchmarks.sweep_spec.EpisodeSpec.key`),
    ``axes`` (the swept fields' values), then ``result`` (the episode's row) or ``error``
    (what the episode raised), ``wall_s``, ``worker`` and ``spec`` (the full, resolved
    specification). A record is written and flushed to disk as soon as its episode ends, so
    an interrupted sweep loses at most the episodes that were running.

    Example:
        >>> results = SweepResults("out/sweep/plant-pushes.jsonl")
        >>> done = results.load()          # key -> record, finished episodes only
        >>> results.append(record)
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        #: What :meth:`load` found: the number of error records, and whether it cut off a
        #: last line that an interrupted write left unfinished.
        self.errors_read = 0
        self.truncated_line = False

    def load(self) -> dict[str, dict[str, Any]]:
        """The finished episodes on file, by key (the last record of a key wins).

        Records of failed episodes (``error``) are not finished: a resumed sweep runs them
        again. An unfinished last line (the process was killed while writing it) is cut off
        the file, so that appending goes on from a whole line.

        Raises:
            SweepResultsError: A line before the last that is not a JSON record.
        """
        self.errors_read, self.truncated_line = 0, False
        if not self.path.exists():
            return {}
        data = self.path.read_bytes()
        lines = data.split(b"\n")
        finished: dict[str, dict[str, Any]] = {}
        offset = 0
        for number, line in enumerate(lines, start=1):
            last = number == len(lines)
            if line.strip():
                record = _record(line)
                if record is None:
                    if last:  # written in part when the sweep was killed
                        with self.path.open("r+b") as file:
                            file.truncate(offset)
                        self.truncated_line = True
                        break
                    raise SweepResultsError(
                        f"{self.path}:{number}: expected one JSON record with a 'key' per line, "
                        f"received {line[:80]!r}; remove the line, or start afresh with --fresh")
                if "result" in record:
                    finished[record["key"]] = record
                else:
                    finished.pop(record["key"], None)
                    self.errors_read += 1
            offset += len(line) + 1
        if data and not data.endswith(b"\n") and not self.truncated_line:
            with self.path.open("ab") as file:  # a whole last record, cut before its newline
                file.write(b"\n")
        return finished

    def append(self, record: Mapping[str, Any]) -> None:
        """Write one record as a line and flush it to disk."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        line = json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n"
        with self.path.open("a", encoding="utf-8") as file:
            file.write(line)
            file.flush()
            os.fsync(file.fileno())

    def clear(self) -> None:
        """Remove the file (a fresh start)."""
        self.path.unlink(missing_ok=True)


def _record(line: bytes) -> dict[str, Any] | None:
    """The record on ``line``, or ``None`` when it is not one."""
    try:
        record = json.loads(line)
    except ValueError:
        return None
    if not isinstance(record, dict) or not isinstance(record.get("key"), str):
        return None
    return record
