"""The GO2's remote: ``LowState_.wireless_remote`` decoded from bytes built by the documented
layout, its sticks as a velocity command, and the remote read on the wire (VelocityInputs)."""

from __future__ import annotations

import struct
from types import SimpleNamespace

import numpy as np
import pytest

from actions.go2.velocity_stream import VelocityStream
from actions.robot.velocity_inputs import VelocityInputs
from wbc.core.errors import ConfigurationError
from wbc.locomotion.gait import VelocityLimits
from wbc.robot_io.wireless_remote import DEAD_ZONE, RemoteState, velocity_from_sticks


def remote_bytes(*, buttons: int = 0, lx: float = 0.0, rx: float = 0.0, ry: float = 0.0,
                 l2: float = 0.0, ly: float = 0.0, head: bytes = b"\x55\x51") -> bytearray:
    """40 bytes as unitree_sdk2's xRockerBtnDataStruct lays them out, field by field: head
    uint8[2], the buttons' uint16, lx, rx, ry, L2, ly as float32, 16 unused bytes."""
    data = bytearray(40)
    data[0:2] = head
    data[2:4] = buttons.to_bytes(2, "little")
    for offset, value in zip((4, 8, 12, 16, 20), (lx, rx, ry, l2, ly), strict=True):
        data[offset:offset + 4] = struct.pack("<f", value)
    data[24:40] = bytes(range(16))  # the unused tail does not matter
    return data


def test_sticks_and_trigger_are_read_from_their_offsets():
    state = RemoteState.decode(remote_bytes(lx=0.25, rx=-0.5, ry=0.75, l2=0.125, ly=-1.0))
    assert (state.lx, state.rx, state.ry, state.l2, state.ly) == (0.25, -0.5, 0.75, 0.125, -1.0)
    assert state.buttons == frozenset()


@pytest.mark.parametrize("bit, name", [(0, "R1"), (1, "L1"), (2, "start"), (3, "select"),
                                       (4, "R2"), (5, "L2"), (6, "F1"), (7, "F2"), (8, "A"),
                                       (9, "B"), (10, "X"), (11, "Y"), (12, "up"),
                                       (13, "right"), (14, "down"), (15, "left")])
def test_each_button_is_its_bit(bit, name):
    assert RemoteState.decode(remote_bytes(buttons=1 << bit)).buttons == {name}


def test_several_buttons_and_signed_bytes_as_some_bindings_give_them():
    data = remote_bytes(buttons=(1 << 1) | (1 << 8) | (1 << 15), lx=0.5)  # L1, A, left
    signed = np.frombuffer(bytes(data), dtype=np.int8).tolist()  # e.g. cyclonedds' byte[]
    assert min(signed) < 0
    state = RemoteState.decode(signed)
    assert state.buttons == {"L1", "A", "left"} and state.lx == 0.5
    assert RemoteState.decode(state.encode()) == state


def test_garbled_sticks_are_clipped_and_a_wrong_size_is_refused():
    state = RemoteState.decode(remote_bytes(lx=float("nan"), ly=3.0, rx=-7.0, l2=-0.5))
    assert (state.lx, state.ly, state.rx, state.l2) == (0.0, 1.0, -1.0, 0.0)
    with pytest.raises(ConfigurationError) as info:
        RemoteState.decode(bytes(24))
    assert str(info.value) == "wireless_remote: expected 40 bytes, received 24"


def test_sticks_map_to_forward_left_and_counter_clockwise_past_the_dead_zone():
    limits = {"forward_mps": 1.0, "lateral_mps": 0.4, "yaw_rate_radps": 1.2}
    full = RemoteState(ly=1.0, lx=-1.0, rx=-1.0)  # left stick up and left, right stick left
    assert velocity_from_sticks(full, **limits) == (1.0, 0.4, 1.2)
    half = RemoteState(ly=-(DEAD_ZONE + 0.5 * (1.0 - DEAD_ZONE)), lx=0.0, rx=1.0)
    forward, lateral, yaw = velocity_from_sticks(half, **limits)
    assert forward == pytest.approx(-0.5) and lateral == 0.0 and yaw == -1.2
    inside = RemoteState(ly=0.9 * DEAD_ZONE, lx=-0.9 * DEAD_ZONE, rx=0.9 * DEAD_ZONE)
    assert velocity_from_sticks(inside, **limits) == (0.0, 0.0, 0.0) and inside.sticks_centred


class RecordingLoop:
    """What VelocityInputs uses of a control loop: the commands it gives (checked by a real
    velocity stream, which starts nothing here), the limits."""

    def __init__(self) -> None:
        self.commands: list[tuple[float, float, float]] = []
        self.context = SimpleNamespace(velocity_stream=VelocityStream(VelocityLimits()))

    def command_velocity(self, forward: float, lateral: float, yaw: float) -> None:
        self.context.velocity_stream.command(forward, lateral, yaw)
        self.commands.append((forward, lateral, yaw))


def test_the_remote_on_the_wire_steers_then_stops_once_when_released():
    loop = RecordingLoop()
    reading = [bytes(remote_bytes())]
    inputs = VelocityInputs(loop, remote=lambda: reading[0])
    inputs.poll(0.0)
    assert loop.commands == []  # centred: the stream is left to other inputs
    reading[0] = bytes(remote_bytes(ly=1.0, rx=1.0))
    inputs.poll(0.01)  # not due yet: read every 20 ms
    inputs.poll(0.02)
    inputs.poll(0.04)
    reading[0] = bytes(remote_bytes())
    inputs.poll(0.06)
    inputs.poll(0.08)
    assert loop.commands == [(1.0, 0.0, -1.2), (1.0, 0.0, -1.2), (0.0, 0.0, 0.0)]
    assert inputs.report() == {"topic_commands": 0, "remote_commands": 3, "refused": 0}


def test_a_bad_remote_reading_is_said_once_and_counted():
    said: list[str] = []
    inputs = VelocityInputs(RecordingLoop(), remote=lambda: bytes(7), say=said.append)
    inputs.poll(0.0)
    inputs.poll(0.02)
    assert said == [("the remote: wireless_remote: expected 40 bytes, received 7; dropped "
                     "(said once, counted in the report)")]
    assert inputs.refused == 2
