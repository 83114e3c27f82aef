"""Whole-body control of the Unitree GO2: description, tasks, QP controller, solver backends."""

from wbc.description import FOOT_FRAMES, JOINT_NAMES, LEGS, Go2Description
from wbc.errors import (
    ConfigurationError, DescriptionNotFoundError, NonFiniteError, ReachabilityError,
    UnknownNameError, WbcError,
)
from wbc.joint_map import JointMap
from wbc.joint_pd_controller import JointPdController

__all__ = [
    "FOOT_FRAMES", "JOINT_NAMES", "LEGS", "ConfigurationError", "DescriptionNotFoundError",
    "Go2Description", "JointMap", "JointPdController", "NonFiniteError", "ReachabilityError",
    "UnknownNameError", "WbcError",
]
