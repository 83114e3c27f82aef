"""Whole-body control of the Unitree GO2: description, QP controller, solver backends, state
estimation.

``from wbc import WholeBodyController`` is the main entry point. The controller and what
depends on the tasks are imported on first use, so that ``tasks`` may use this package's
leaf modules (``wbc.errors``, ``wbc.validation``) without an import cycle.
"""

from importlib import import_module
from typing import Any

from wbc.description import FOOT_FRAMES, FOOT_RADIUS_M, JOINT_NAMES, LEGS, Go2Description
from wbc.errors import (
    ConfigurationError,
    DescriptionNotFoundError,
    NonFiniteError,
    ReachabilityError,
    UnknownNameError,
    WbcError,
)
from wbc.joint_map import JointMap

_LAZY = {
    "WholeBodyController": "wbc.whole_body_controller",
    "ControllerConfig": "wbc.controller_config",
    "ControlOutput": "wbc.control_output",
    "ControlStatus": "wbc.control_output",
    "LegLift": "wbc.leg_lift",
    "LegLiftTiming": "wbc.leg_lift",
    "LiftPhase": "wbc.leg_lift",
    "BalanceController": "wbc.balance_controller",
    "JointPdController": "wbc.joint_pd_controller",
    "JointReference": "wbc.joint_reference",
    "MotorCommand": "wbc.motor_command",
    "SdkLowState": "wbc.unitree_sdk",
    "SdkMotorCommand": "wbc.unitree_sdk",
    "PlacoController": "wbc.placo_controller",
    "ProblemBuilder": "wbc.problem_builder",
    "Regularization": "wbc.problem_builder",
    "SupportPolygon": "wbc.support_polygon",
    "available_backends": "wbc.backends",
    "SensorRecord": "wbc.sensor_record",
    "StateEstimator": "wbc.state_estimator",
    "StateEstimate": "wbc.state_estimator",
    "EstimatorConfig": "wbc.state_estimator",
    "InvariantEkf": "wbc.invariant_ekf",
    "InvariantEkfConfig": "wbc.invariant_ekf",
    "make_estimator": "wbc.estimators",
    "LegKinematics": "wbc.leg_kinematics",
    "sensor_record_from_message": "wbc.unitree_sdk",
}

__all__ = [
    "FOOT_FRAMES", "FOOT_RADIUS_M", "JOINT_NAMES", "LEGS", "ConfigurationError",
    "DescriptionNotFoundError", "Go2Description", "JointMap", "NonFiniteError",
    "ReachabilityError", "UnknownNameError", "WbcError", *_LAZY,
]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'wbc' has no attribute {name!r}")
