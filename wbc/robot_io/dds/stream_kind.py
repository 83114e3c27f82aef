"""Which kind of ``rt/lowstate`` stream a robot sends, and what can be checked on it:
:class:`StreamKind`.

Three framings exist (read in Unitree's sources, measured on their simulators):

``go2``
    A GO2, or ``go2-wbc bridge``: ``head`` FE EF, a valid CRC, a ``tick`` that counts.
``unitree-cpp``
    Unitree's C++ simulator (unitree_mujoco ``simulate``, publishing through unitree_sdk2's
    ``dds_wrapper`` ``go2_pub.h``): ``head`` 00 00 (never set), a valid CRC (set before each
    write), ``tick`` the simulated time in milliseconds (``round(time / 1 ms)``).
``unitree-python``
    Unitree's Python simulator (unitree_mujoco ``simulate_python``): ``head`` 00 00,
    ``crc`` 0 (not computed), ``tick`` 0 always, ``level_flag`` 0, ``foot_force`` 0.

A frame's framing (:func:`framing_of`) follows from its ``head`` and its CRC alone; whether
its tick counts is learnt from several samples (:class:`~wbc.robot_io.dds.low_state_stream.
LowStateStream`). A stream whose tick does not count has its samples told apart by their
content.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wbc.robot_io.dds.c_layout import HEAD, crc_ok

#: The framings, in the order :func:`framing_of` tries them.
GO2, UNITREE_CPP, UNITREE_PYTHON = "go2", "unitree-cpp", "unitree-python"
FRAMINGS = (GO2, UNITREE_CPP, UNITREE_PYTHON)
#: Who sends each framing.
SENDERS = {
    GO2: "a GO2 or go2-wbc bridge",
    UNITREE_CPP: "Unitree's C++ simulator (unitree_mujoco simulate)",
    UNITREE_PYTHON: "Unitree's Python simulator (unitree_mujoco simulate_python)",
}
_ZERO_HEAD = (0x00, 0x00)
_HEAD_BYTES, _ZERO_HEAD_BYTES = bytes(HEAD), bytes(_ZERO_HEAD)


def _head_text(head: tuple[int, ...]) -> str:
    return " ".join(f"{b:02X}" for b in head)


def framing_of(record: np.ndarray) -> tuple[str | None, str]:
    """The framing of one ``LowState_`` record, or ``None`` and why it fits none.

    Returns:
        ``(framing, "")`` for a frame of one of :data:`FRAMINGS`; ``(None, reason)`` for a
        frame that fits none, the reason naming the field, what was received and what is
        valid.
    """
    head = record["head"].tobytes()  # bytes compare: ~5 times faster than by element
    if head == _HEAD_BYTES:
        if crc_ok(record):
            return GO2, ""
        return None, (f"LowState_.crc: 0x{int(record['crc']):08X} does not match the content "
                      f"(a frame with head FE EF carries a CRC)")
    if head == _ZERO_HEAD_BYTES:
        crc = int(record["crc"])
        if crc == 0:  # a valid CRC of 0 is one in 2^32: not worth the check's 4 us
            return UNITREE_PYTHON, ""
        if crc_ok(record):
            return UNITREE_CPP, ""
        return None, (f"LowState_.crc: 0x{crc:08X} does not match the content (valid: the "
                      f"content's CRC, or 0 for a stream without one)")
    return None, (f"LowState_.head: expected FE EF (a GO2) or 00 00 (Unitree's simulators), "
                  f"received {_head_text(tuple(head))}")


@dataclass(frozen=True)
class StreamKind:
    """A stream's framing and whether its tick counts.

    Attributes:
        framing: One of :data:`FRAMINGS`.
        ticks: The tick advanced over the first samples: a sample with the tick of the one
            before is a repeat. Otherwise samples are told apart by their content (the same
            bytes again are a repeat).
    """

    framing: str
    ticks: bool

    @property
    def sender(self) -> str:
        """Who sends this framing (:data:`SENDERS`)."""
        return SENDERS[self.framing]

    @property
    def head(self) -> str:
        """The ``head`` every frame must carry, as text."""
        return _head_text(HEAD) if self.framing == GO2 else _head_text(_ZERO_HEAD)

    @property
    def crc_checked(self) -> bool:
        """Whether each frame's CRC is checked (the stream carries one)."""
        return self.framing != UNITREE_PYTHON

    def checks(self) -> str:
        """What is checked on each frame and how a new sample is told from a repeat."""
        crc = "CRC checked" if self.crc_checked else "no CRC (sent as 0: not checked)"
        new = ("a new sample has a new tick" if self.ticks else
               "tick not counting: a new sample has new content (the same bytes again are a "
               "repeat)")
        return f"head {self.head}, {crc}; {new}"

    def describe(self) -> str:
        """One line: the kind, who sends it, what is checked."""
        return f"{self.framing} ({self.sender}): {self.checks()}"
