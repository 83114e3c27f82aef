"""Whole-body control of the Unitree GO2: description, QP controller, solver backends, state
estimation.

``from wbc import WholeBodyController`` is the main entry point. The public names load on first
use (PEP 562): importing a leaf module such as ``wbc.core.errors``, as the tasks do, loads that
module alone, not the controller, so ``wbc`` and ``tasks`` import in either order. Type
checkers and editors read the explicit imports below.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from wbc.core.package_shadowing import check_not_shadowed

# A user's own tasks.py or sim.py next to their script would break the library with an
# unrelated ImportError: name the file to rename instead, on the library's first import.
check_not_shadowed()

if TYPE_CHECKING:  # the same names, for type checkers and editors
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
    from wbc.estimation.linear_kalman_filter import LinearKalmanFilter
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

#: The public names by module: the runtime twin of the imports above (tests/test_layering.py
#: checks that the two list the same names).
_NAMES_BY_MODULE: dict[str, tuple[str, ...]] = {
    "wbc.backends": ("available_backends",),
    "wbc.controller.balance_controller": ("BalanceController",),
    "wbc.controller.contact_schedule": ("ContactSchedule",),
    "wbc.controller.control_output": ("ControlOutput", "ControlStatus"),
    "wbc.controller.controller_config": (
        "ContactSettings", "ControllerConfig", "CostWeights", "LimitSettings", "ShapingSettings",
        "SolverSettings", "TaskGains",
    ),
    "wbc.controller.joint_pd_controller": ("JointPdController",),
    "wbc.controller.joint_reference": ("JointReference",),
    "wbc.controller.placo_controller": ("PlacoController",),
    "wbc.controller.problem_builder": ("ProblemBuilder", "Regularization"),
    "wbc.controller.whole_body_controller": ("WholeBodyController",),
    "wbc.core.errors": (
        "ConfigurationError", "DescriptionNotFoundError", "NonFiniteError", "OrderMismatchError",
        "ReachabilityError", "UnknownNameError", "WbcError",
    ),
    "wbc.estimation.estimator_config": ("EstimatorConfig",),
    "wbc.estimation.estimators": ("make_estimator",),
    "wbc.estimation.invariant_ekf": ("InvariantEkf", "InvariantEkfConfig"),
    "wbc.estimation.linear_kalman_filter": ("LinearKalmanFilter",),
    "wbc.estimation.state_estimate": ("StateEstimate",),
    "wbc.estimation.state_estimator": ("StateEstimator",),
    "wbc.model.description": (
        "FOOT_FRAMES", "FOOT_RADIUS_M", "JOINT_NAMES", "LEGS", "UNITREE_SDK_JOINT_NAMES",
        "UNITREE_SDK_LEGS", "Go2Description",
    ),
    "wbc.model.joint_map": ("JointMap",),
    "wbc.model.leg_kinematics": ("LegKinematics",),
    "wbc.model.orders": ("DESCRIPTION_ORDERS", "UNITREE_SDK_ORDERS", "Orders"),
    "wbc.model.support_polygon": ("SupportPolygon",),
    "wbc.motions.leg_lift": ("LegLift", "LegLiftTiming", "LiftPhase"),
    "wbc.robot_io.motor_command": ("MotorCommand",),
    "wbc.robot_io.sdk_low_state": ("SdkLowState", "sensor_record_from_message"),
    "wbc.robot_io.sdk_motor_command": ("SdkMotorCommand",),
    "wbc.robot_io.sensor_record": ("SensorRecord",),
}
_HOMES = {name: module for module, names in _NAMES_BY_MODULE.items() for name in names}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    """Loads a public name from its module on first use and keeps it here."""
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'wbc' has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))
