"""Acceleration-level tasks and QP constraints for whole-body control, with compiled kernels."""

from tasks.base_orientation_task import BaseOrientationTask
from tasks.com_task import ComTask
from tasks.constraint import Constraint, ConstraintBlock, Elimination
from tasks.contact_force_task import ContactForceTask
from tasks.contact_task import ContactTask
from tasks.floating_base_dynamics import FloatingBaseDynamics
from tasks.frame_position_task import FramePositionTask
from tasks.friction_cones import FrictionCones
from tasks.joint_limits import JointLimits
from tasks.posture_task import PostureTask
from tasks.stance_contacts import StanceContacts
from tasks.support_polygon_barrier import SupportPolygonBarrier
from tasks.task import Task
from tasks.task_block import TaskBlock
from tasks.torque_limits import TorqueLimits
from tasks.variable_layout import VariableLayout, force_variable, slack_variable
from wbc.model.kinematics import RobotKinematics

__all__ = [
    "BaseOrientationTask", "ComTask", "Constraint", "ConstraintBlock", "ContactForceTask",
    "ContactTask", "Elimination", "FloatingBaseDynamics", "FramePositionTask", "FrictionCones",
    "JointLimits", "PostureTask", "RobotKinematics", "StanceContacts", "SupportPolygonBarrier",
    "Task", "TaskBlock", "TorqueLimits", "VariableLayout", "force_variable", "slack_variable",
]
