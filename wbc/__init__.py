"""Whole-body control of the Unitree GO2: description, QP controller, solver backends, state
estimation.

``from wbc import WholeBodyController`` is the main entry point. Every public name is
imported here explicitly, so type checkers and editors see its type.

``tasks`` uses this package's leaf modules (``wbc.errors``, ``wbc.validation``) and the
controller imports ``tasks``: ``tasks`` imports this package before any module of its own,
and the controller imports the tasks' modules rather than the package, so either package may
be imported first.
"""

from wbc.backends import available_backends
from wbc.balance_controller import BalanceController
from wbc.control_output import ControlOutput, ControlStatus
from wbc.controller_config import ControllerConfig
from wbc.description import FOOT_FRAMES, FOOT_RADIUS_M, JOINT_NAMES, LEGS, Go2Description
from wbc.errors import (
    ConfigurationError,
    DescriptionNotFoundError,
    NonFiniteError,
    ReachabilityError,
    UnknownNameError,
    WbcError,
)
from wbc.estimators import make_estimator
from wbc.invariant_ekf import InvariantEkf, InvariantEkfConfig
from wbc.joint_map import JointMap
from wbc.joint_pd_controller import JointPdController
from wbc.joint_reference import JointReference
from wbc.leg_kinematics import LegKinematics
from wbc.leg_lift import LegLift, LegLiftTiming, LiftPhase
from wbc.motor_command import MotorCommand
from wbc.placo_controller import PlacoController
from wbc.problem_builder import ProblemBuilder, Regularization
from wbc.sensor_record import SensorRecord
from wbc.state_estimator import EstimatorConfig, StateEstimate, StateEstimator
from wbc.support_polygon import SupportPolygon
from wbc.unitree_sdk import SdkLowState, SdkMotorCommand, sensor_record_from_message
from wbc.whole_body_controller import WholeBodyController

__all__ = [
    "FOOT_FRAMES",
    "FOOT_RADIUS_M",
    "JOINT_NAMES",
    "LEGS",
    "BalanceController",
    "ConfigurationError",
    "ControlOutput",
    "ControlStatus",
    "ControllerConfig",
    "DescriptionNotFoundError",
    "EstimatorConfig",
    "Go2Description",
    "InvariantEkf",
    "InvariantEkfConfig",
    "JointMap",
    "JointPdController",
    "JointReference",
    "LegKinematics",
    "LegLift",
    "LegLiftTiming",
    "LiftPhase",
    "MotorCommand",
    "NonFiniteError",
    "PlacoController",
    "ProblemBuilder",
    "ReachabilityError",
    "Regularization",
    "SdkLowState",
    "SdkMotorCommand",
    "SensorRecord",
    "StateEstimate",
    "StateEstimator",
    "SupportPolygon",
    "UnknownNameError",
    "WbcError",
    "WholeBodyController",
    "available_backends",
    "make_estimator",
    "sensor_record_from_message",
]
