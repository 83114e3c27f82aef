"""Whole-body control of the Unitree GO2: description, QP controller, solver backends, state
estimation.

``from wbc import WholeBodyController`` is the main entry point. Every public name is
imported here explicitly, so type checkers and editors see its type.

``tasks`` uses this package's leaf modules (``wbc.core.errors``, ``wbc.core.validation``) and the
controller imports ``tasks``: ``tasks`` imports this package before any module of its own,
and the controller imports the tasks' modules rather than the package, so either package may
be imported first.
"""

from wbc.backends import available_backends
from wbc.controller.balance_controller import BalanceController
from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.controller.controller_config import (
    ContactSettings,
    ControllerConfig,
    CostWeights,
    LimitSettings,
    ShapingSettings,
    SolverSettings,
    TaskGains,
)
from wbc.controller.joint_pd_controller import JointPdController
from wbc.controller.joint_reference import JointReference
from wbc.controller.placo_controller import PlacoController
from wbc.controller.problem_builder import ProblemBuilder, Regularization
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import (
    ConfigurationError,
    DescriptionNotFoundError,
    NonFiniteError,
    OrderMismatchError,
    ReachabilityError,
    UnknownNameError,
    WbcError,
)
from wbc.estimation.estimator_config import EstimatorConfig
from wbc.estimation.estimators import make_estimator
from wbc.estimation.invariant_ekf import InvariantEkf, InvariantEkfConfig
from wbc.estimation.state_estimate import StateEstimate
from wbc.estimation.state_estimator import StateEstimator
from wbc.model.description import (
    FOOT_FRAMES,
    FOOT_RADIUS_M,
    JOINT_NAMES,
    LEGS,
    UNITREE_SDK_JOINT_NAMES,
    UNITREE_SDK_LEGS,
    Go2Description,
)
from wbc.model.joint_map import JointMap
from wbc.model.leg_kinematics import LegKinematics
from wbc.model.orders import DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS, Orders
from wbc.model.support_polygon import SupportPolygon
from wbc.motions.leg_lift import LegLift, LegLiftTiming, LiftPhase
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sdk_low_state import SdkLowState, sensor_record_from_message
from wbc.robot_io.sdk_motor_command import SdkMotorCommand
from wbc.robot_io.sensor_record import SensorRecord

__all__ = [
    "DESCRIPTION_ORDERS",
    "FOOT_FRAMES",
    "FOOT_RADIUS_M",
    "JOINT_NAMES",
    "LEGS",
    "UNITREE_SDK_JOINT_NAMES",
    "UNITREE_SDK_LEGS",
    "UNITREE_SDK_ORDERS",
    "BalanceController",
    "ConfigurationError",
    "ContactSchedule",
    "ContactSettings",
    "ControlOutput",
    "ControlStatus",
    "ControllerConfig",
    "CostWeights",
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
    "LimitSettings",
    "MotorCommand",
    "NonFiniteError",
    "OrderMismatchError",
    "Orders",
    "PlacoController",
    "ProblemBuilder",
    "ReachabilityError",
    "Regularization",
    "SdkLowState",
    "SdkMotorCommand",
    "SensorRecord",
    "ShapingSettings",
    "SolverSettings",
    "StateEstimate",
    "StateEstimator",
    "SupportPolygon",
    "TaskGains",
    "UnknownNameError",
    "WbcError",
    "WholeBodyController",
    "available_backends",
    "make_estimator",
    "sensor_record_from_message",
]
