"""The velocity commands a GO2's loop takes on its wire (``go2-wbc run --dds``): the
``rt/cmd_vel`` topic (:mod:`wbc.robot_io.dds.cmd_vel_topic`) and, with ``--remote``, the
GO2's own remote read from ``LowState_.wireless_remote``
(:mod:`wbc.robot_io.wireless_remote`); both go to the loop's velocity stream
(:meth:`~actions.robot.control_loop.ControlLoop.command_velocity`).

A callback of the wall-clock loop (:class:`~actions.robot.realtime_loop.RealtimeLoop`),
called after each tick, on the loop's thread.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.cmd_vel_topic import CmdVelReader
from wbc.robot_io.dds.domain_config import DomainHandle, join_domain
from wbc.robot_io.wireless_remote import RemoteState, velocity_from_sticks

logger = logging.getLogger(__name__)

#: How often [s] the remote's bytes are read (its sticks move at a hand's pace).
REMOTE_PERIOD_S = 0.02


class VelocityInputs:
    """Feeds ``loop``'s velocity stream from ``rt/cmd_vel`` and, optionally, the remote.

    Args:
        loop: The GO2's control loop (its ``command_velocity`` and ``context``).
        domain_id, interface: Where to read ``rt/cmd_vel`` (``None``: not read).
        remote: Returns the newest ``wireless_remote`` bytes (``DdsRobot.wireless_remote``);
            ``None``: the remote is not read. Its sticks, out of their dead zone, command
            forward (left stick up), leftward (left stick left) and turning (right stick
            left) at up to the walking limits; sticks back at the centre send one zero
            command (a stop).
        say: Prints a line (the first refused command of each input, with the reason).
    """

    def __init__(self, loop: Any, *, domain_id: int | None = None, interface: str = "lo",
                 remote: Callable[[], bytes] | None = None,
                 say: Callable[[str], None] = logger.warning) -> None:
        self.loop = loop
        self._say = say
        self._dds: DomainHandle | None = None
        self._reader: CmdVelReader | None = None
        if domain_id is not None:
            self._dds = join_domain(interface, domain_id=domain_id)
            self._reader = CmdVelReader(self._dds)
        self._remote = remote
        self._remote_due_s = 0.0
        self._remote_moving = False
        #: Commands taken from ``rt/cmd_vel`` and from the remote, and those refused.
        self.topic_commands = 0
        self.remote_commands = 0
        self.refused = 0

    def __call__(self, rt: Any) -> None:
        """The wall-clock loop's callback: :meth:`poll` at the robot's time."""
        self.poll(rt.loop.robot.time_s)

    def poll(self, now_s: float) -> None:
        """Take the newest ``rt/cmd_vel`` command and, when due, read the remote."""
        reader = self._reader
        if reader is not None:
            command = reader.take()
            if command is not None:
                self.topic_commands += 1
                self._command(command, "rt/cmd_vel")
        remote = self._remote
        if remote is not None and now_s >= self._remote_due_s:
            self._remote_due_s = now_s + REMOTE_PERIOD_S
            self._read_remote(remote)

    def _read_remote(self, remote: Callable[[], bytes]) -> None:
        try:
            state = RemoteState.decode(remote())
        except ConfigurationError as err:
            self._refuse("the remote", str(err))
            return
        if state.sticks_centred:
            if self._remote_moving:  # released: stop once, then leave the stream to others
                self._remote_moving = False
                self.remote_commands += 1
                self._command((0.0, 0.0, 0.0), "the remote")
            return
        self._remote_moving = True
        limits = self.loop.context.velocity_stream.limits
        self.remote_commands += 1
        self._command(velocity_from_sticks(
            state, forward_mps=limits.forward_mps, lateral_mps=limits.lateral_mps,
            yaw_rate_radps=limits.yaw_rate_radps), "the remote")

    def _command(self, command: tuple[float, float, float], source: str) -> None:
        try:
            self.loop.command_velocity(*command)
        except ConfigurationError as err:
            self._refuse(source, str(err))

    def _refuse(self, source: str, why: str) -> None:
        if not self.refused:
            self._say(f"{source}: {why}; dropped (said once, counted in the report)")
        self.refused += 1

    def report(self) -> dict[str, int]:
        """The counters, for the run's report."""
        return {"topic_commands": self.topic_commands, "remote_commands": self.remote_commands,
                "refused": self.refused}

    def close(self) -> None:
        """Delete the reader and leave the domain; idempotent."""
        reader, self._reader = self._reader, None
        if reader is not None:
            reader.close()
        dds, self._dds = self._dds, None
        if dds is not None:
            dds.close()
