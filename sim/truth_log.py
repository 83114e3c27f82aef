"""Every truth sample a bridge published, kept for an ``.npz`` at exit: :class:`TruthLog`."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from wbc.model.description import JOINT_NAMES, LEGS
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_DTYPE


class TruthLog:
    """Copies of :data:`wbc.robot_io.dds.sim_truth.SIM_TRUTH_DTYPE` records, in chunks (440 B a
    sample: about 0.8 GB an hour at 500 Hz).

    :meth:`arrays` gives the fields of ``rt/wbc/sim/truth`` as arrays with one row a sample:
    ``tick`` (n,), ``t_s`` (n,), ``q`` (n, 19), ``v`` (n, 18), ``foot_position_m``
    (n, 4, 3), ``foot_force_n`` (n, 4), in the conventions of
    :mod:`wbc.robot_io.dds.sim_truth`, with ``joint_names`` (12,) and ``leg_names`` (4,) for the
    orders.
    """

    _CHUNK = 4096

    def __init__(self) -> None:
        self._chunks: list[np.ndarray] = []
        self._current = np.zeros(self._CHUNK, dtype=SIM_TRUTH_DTYPE)
        self._count = 0

    def __len__(self) -> int:
        return len(self._chunks) * self._CHUNK + self._count

    def append(self, record: np.ndarray) -> None:
        """Keep a copy of one record."""
        if self._count == self._CHUNK:
            self._chunks.append(self._current)
            self._current = np.zeros(self._CHUNK, dtype=SIM_TRUTH_DTYPE)
            self._count = 0
        self._current[self._count] = record
        self._count += 1

    def arrays(self) -> dict[str, np.ndarray]:
        """The samples' fields, one row a sample, and the joint and leg names."""
        records = np.concatenate([*self._chunks, self._current[:self._count]])
        arrays = {name: np.ascontiguousarray(records[name])
                  for name in SIM_TRUTH_DTYPE.names or ()}
        arrays["joint_names"] = np.array(JOINT_NAMES)
        arrays["leg_names"] = np.array(LEGS)
        return arrays

    def save(self, path: Path | str) -> int:
        """Write :meth:`arrays` to a compressed ``.npz``; returns the number of samples."""
        arrays: dict[str, Any] = self.arrays()
        np.savez_compressed(path, **arrays)
        return len(self)
