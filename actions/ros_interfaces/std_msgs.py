"""``std_msgs``: the header that stamps data with a time and a frame."""

from __future__ import annotations

from dataclasses import dataclass, field

from actions.messages import Message, Time


@dataclass(slots=True)
class Header(Message):
    """``std_msgs/Header``: when (``stamp``, simulated time) and in which frame data was given."""

    stamp: Time = field(default_factory=Time)
    frame_id: str = ""
