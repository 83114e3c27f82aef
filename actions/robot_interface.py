"""The robot as behaviours see it: state in, motor commands out, joints wired by name.

Sim-to-real: a behaviour never talks to MuJoCo or to a motor driver. It talks to a
:class:`RobotInterface` in the robot's own joint order (a MuJoCo plant, the Unitree SDK's
FR, FL, RR, RL order, ...), wrapped in a :class:`MappedRobot` that converts, by joint name,
to the description order the controller uses. Swapping the simulator for the real robot
changes the interface object and its names, not the behaviour code.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from wbc.description import JOINT_NAMES
from wbc.joint_map import JointMap
from wbc.motor_command import MotorCommand
from wbc.validation import as_vector


@runtime_checkable
class RobotInterface(Protocol):
    """A robot in its own joint order."""

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The robot's joints, in the order its arrays use."""

    @property
    def time_s(self) -> float:
        """The robot's clock [s] (simulated time for a simulator)."""

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q (19,), v (18,))``: Pinocchio-convention base, joints in the robot's order."""

    def write_command(self, command: MotorCommand) -> None:
        """Hand the motor drivers one command (arrays (12,) in the robot's order).

        The drivers apply ``tau_ff + kp (q_des - q) + kd (dq_des - dq)`` until the next
        command, one control period later. A plant that takes bare torques applies
        :meth:`~wbc.motor_command.MotorCommand.torque_at` the state it measured.
        """


class MappedRobot:
    """A :class:`RobotInterface` seen in the description's joint order.

    Args:
        robot: The robot, in its own joint order.
        aliases: Its joint names mapped to the description's, where they differ.
    """

    def __init__(self, robot: RobotInterface, *, aliases: dict[str, str] | None = None):
        self.robot = robot
        self.joint_map = JointMap(robot.joint_names, aliases=aliases)
        #: The robot's order is the description's: arrays are copied, not reordered.
        self._same_order = bool(np.array_equal(self.joint_map.index, np.arange(len(JOINT_NAMES))))

    @property
    def time_s(self) -> float:
        """The robot's clock [s]."""
        return self.robot.time_s

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)`` with the joints in the description order."""
        q, v = self.robot.read_state()
        q = as_vector("q", q, 19, finite=False)
        v = as_vector("v", v, 18, finite=False)
        if not self._same_order:
            q[7:] = q[7:][self.joint_map.inverse]
            v[6:] = v[6:][self.joint_map.inverse]
        return q, v

    def write_command(self, command: MotorCommand) -> None:
        """A motor command in the description order, sent in the robot's order (a copy)."""
        if self._same_order:
            self.robot.write_command(command.copy())
        else:
            self.robot.write_command(command.reordered(self.joint_map.index))
