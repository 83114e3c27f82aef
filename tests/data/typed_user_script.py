"""A user's script, type-checked (not run) by tests/test_typing.py: the public names as a type
checker sees them from outside the packages.

Each ``reveal_type`` says, after ``# expect:``, what the revealed type must contain (never
``Any``); mypy runs with ``--warn-unused-ignores``, so the deliberate mistakes below, each
with its ``type: ignore``, must be caught.
"""

from typing import reveal_type

import numpy as np

from actions import ControlLoop as RobotLoop
from actions import GoalStatus, HighFiveGoal, RobotInterface
from sim.control_loop import ControlLoop
from wbc import (
    UNITREE_SDK_ORDERS,
    ControllerConfig,
    ControlOutput,
    Go2Description,
    InvariantEkf,
    SensorRecord,
    StateEstimator,
    WholeBodyController,
    available_backends,
    make_estimator,
)

reveal_type(WholeBodyController)  # expect: whole_body_controller.WholeBodyController
controller = WholeBodyController(ControllerConfig())
reveal_type(controller.step)  # expect: -> wbc.controller.control_output.ControlOutput
q = Go2Description().pose("standing")
output: ControlOutput = controller.step(q, np.zeros(18))
reveal_type(output.status)  # expect: wbc.controller.control_output.ControlStatus
controller.step(q)  # type: ignore[call-arg]

reveal_type(ControlLoop.simulated)  # expect: -> sim.control_loop.ControlLoop
loop = ControlLoop.simulated(control_period_s=2e-3)
client = loop.client("high_five")
reveal_type(client.send_goal_and_wait)  # expect: -> actions.responses.WrappedResult
outcome = client.send_goal_and_wait(HighFiveGoal(target_height=0.3, hold_seconds=0))
reveal_type(outcome.status)  # expect: actions.goal_status.GoalStatus
succeeded: bool = outcome.status is GoalStatus.SUCCEEDED
HighFiveGoal(height=0.3)  # type: ignore[call-arg]

reveal_type(StateEstimator)  # expect: -> wbc.estimation.linear_kalman_filter.LinearKalmanFilter
reveal_type(InvariantEkf)  # expect: -> wbc.estimation.invariant_ekf.InvariantEkf
reveal_type(make_estimator)  # expect: -> wbc.estimation.estimator_base.EstimatorBase
reveal_type(SensorRecord)  # expect: -> wbc.robot_io.sensor_record.SensorRecord
reveal_type(available_backends())  # expect: list[str]
reveal_type(RobotLoop)  # expect: -> actions.robot.control_loop.ControlLoop
reveal_type(loop.robot.robot_orders)  # expect: wbc.model.orders.Orders
robot: RobotInterface = loop.robot.robot
reveal_type(SensorRecord.zeros(UNITREE_SDK_ORDERS).orders)  # expect: wbc.model.orders.Orders
SensorRecord.zeros("sdk")  # type: ignore[arg-type]
