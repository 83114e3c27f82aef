"""Acceleration-level tasks for whole-body control: error, Jacobian and drift from Pinocchio."""

from tasks.base_orientation_task import BaseOrientationTask
from tasks.com_task import ComTask
from tasks.contact_task import ContactTask
from tasks.frame_position_task import FramePositionTask
from tasks.posture_task import PostureTask
from tasks.task import Task

__all__ = [
    "BaseOrientationTask", "ComTask", "ContactTask", "FramePositionTask", "PostureTask", "Task",
]
