"""The GO2's own remote as ``LowState_.wireless_remote`` carries it (40 bytes), decoded into
sticks and buttons (:class:`RemoteState`), and its sticks as a velocity command
(:func:`velocity_from_sticks`).

The layout, as Unitree's SDK declares it (unitree_sdk2, ``xRockerBtnDataStruct`` in its
examples' ``gamepad.hpp``; little-endian, as the robot's computers and this host are):

====== ======= ===============================================================================
bytes  type    field
====== ======= ===============================================================================
0-1    uint8   ``head`` (not used)
2-3    uint16  buttons, bit 0 first: R1, L1, start, select, R2, L2, F1, F2, A, B, X, Y, up,
               right, down, left
4-7    float32 ``lx``: left stick, right positive, [-1, 1]
8-11   float32 ``rx``: right stick, right positive
12-15  float32 ``ry``: right stick, forward positive
16-19  float32 ``L2``: the L2 trigger's travel, [0, 1]
20-23  float32 ``ly``: left stick, forward positive
24-39  uint8   unused
====== ======= ===============================================================================

Unitree's own example maps the sticks as forward ``ly``, left ``-lx``, yaw rate ``-rx``
(counter-clockwise positive): :func:`velocity_from_sticks` does the same.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass

from wbc.core.errors import ConfigurationError

#: Size [bytes] of ``wireless_remote``.
REMOTE_BYTES = 40
#: Button names by bit, bit 0 first.
BUTTONS = ("R1", "L1", "start", "select", "R2", "L2", "F1", "F2", "A", "B", "X", "Y", "up",
           "right", "down", "left")
#: Stick travel below which a stick counts as centred (Unitree's example uses 0.01; a worn
#: stick rests a few percent off centre).
DEAD_ZONE = 0.05
_LAYOUT = struct.Struct("<2xH5f")  # head skipped, buttons, lx, rx, ry, L2, ly


@dataclass(frozen=True)
class RemoteState:
    """One reading of the remote.

    Attributes:
        lx, ly: Left stick, right and forward positive, [-1, 1].
        rx, ry: Right stick, right and forward positive, [-1, 1].
        l2: The L2 trigger's travel, [0, 1].
        buttons: The names of the buttons pressed (:data:`BUTTONS`).
    """

    lx: float = 0.0
    ly: float = 0.0
    rx: float = 0.0
    ry: float = 0.0
    l2: float = 0.0
    buttons: frozenset[str] = frozenset()

    @classmethod
    def decode(cls, data: bytes | bytearray | Sequence[int]) -> RemoteState:
        """The remote's state from the 40 bytes of ``wireless_remote`` (any byte values:
        ``uint8`` or the ``int8`` some bindings give).

        A stick reading that is not finite or beyond [-1, 1] (a garbled frame) is clipped
        into the range, NaN read as centred.

        Raises:
            ConfigurationError: Not 40 bytes.
        """
        raw = bytes(b & 0xFF for b in data) if not isinstance(data, (bytes, bytearray)) else data
        if len(raw) != REMOTE_BYTES:
            raise ConfigurationError(
                f"wireless_remote: expected {REMOTE_BYTES} bytes, received {len(raw)}")
        bits, lx, rx, ry, l2, ly = _LAYOUT.unpack_from(raw)
        pressed = frozenset(name for i, name in enumerate(BUTTONS) if bits >> i & 1)
        return cls(lx=_axis(lx), ly=_axis(ly), rx=_axis(rx), ry=_axis(ry),
                   l2=max(0.0, _axis(l2)), buttons=pressed)

    def encode(self) -> bytes:
        """The 40 bytes a GO2 would send for this state (head zero): for tests and peers."""
        bits = sum(1 << BUTTONS.index(name) for name in self.buttons)
        return _LAYOUT.pack(bits, self.lx, self.rx, self.ry, self.l2, self.ly).ljust(
            REMOTE_BYTES, b"\0")

    @property
    def sticks_centred(self) -> bool:
        """Both sticks within :data:`DEAD_ZONE` of the centre."""
        return all(abs(axis) < DEAD_ZONE for axis in (self.lx, self.ly, self.rx))


def _axis(value: float) -> float:
    return 0.0 if math.isnan(value) else min(1.0, max(-1.0, value))


def _shaped(axis: float) -> float:
    """A stick's travel past the dead zone, rescaled to [-1, 1] (no jump at its edge)."""
    travel = abs(axis)
    if travel < DEAD_ZONE:
        return 0.0
    return math.copysign((travel - DEAD_ZONE) / (1.0 - DEAD_ZONE), axis)


def velocity_from_sticks(state: RemoteState, *, forward_mps: float, lateral_mps: float,
                         yaw_rate_radps: float) -> tuple[float, float, float]:
    """The velocity command the sticks ask for: forward from ``ly``, left from ``-lx``, yaw
    rate (counter-clockwise) from ``-rx``, each a stick's travel past the dead zone times
    its limit.

    Args:
        state: The remote's reading.
        forward_mps, lateral_mps: Speeds [m/s] at full travel.
        yaw_rate_radps: Turning rate [rad/s] at full travel.

    Returns:
        ``(forward_mps, lateral_mps, yaw_rate_radps)``; zeros with the sticks centred.
    """
    return (_shaped(state.ly) * forward_mps, -_shaped(state.lx) * lateral_mps,
            -_shaped(state.rx) * yaw_rate_radps)
