"""The robot loop: the robot interface and the capabilities a robot may declare, the loop
whose one tick, in stages, reads the robot, estimates its state, ticks the actions and
writes the motor command (a simulator or a real GO2), a recorded robot.

``from actions.robot import ControlLoop, RobotInterface`` (or ``from actions import ...``):
the names below are imported on first use, so that a module of this package imported alone
(the robot interface, in the simulator's processes) does not pull in the controller.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from actions.robot.control_loop import ControlLoop
    from actions.robot.loop_behaviours import LoopBehaviours
    from actions.robot.robot_capabilities import (
        AnswersTicks,
        AppliesCommandAtOnce,
        CountsSkips,
        DescribesStream,
        ReportsStats,
        StalenessLimited,
        StateWaiting,
    )
    from actions.robot.robot_interface import MappedRobot, RobotInterface, TrueState, check_robot
    from actions.robot.robot_loop import RobotLoop
    from actions.robot.robot_tick import Stage, StageTimes, TickFilter, TickTimer

_EXPORTS = {
    "ControlLoop": "actions.robot.control_loop",
    "RobotLoop": "actions.robot.robot_loop",
    "LoopBehaviours": "actions.robot.loop_behaviours",
    "Stage": "actions.robot.robot_tick",
    "StageTimes": "actions.robot.robot_tick",
    "TickFilter": "actions.robot.robot_tick",
    "TickTimer": "actions.robot.robot_tick",
    "MappedRobot": "actions.robot.robot_interface",
    "RobotInterface": "actions.robot.robot_interface",
    "TrueState": "actions.robot.robot_interface",
    "check_robot": "actions.robot.robot_interface",
    **dict.fromkeys(("AnswersTicks", "AppliesCommandAtOnce", "CountsSkips", "DescribesStream",
                     "ReportsStats", "StalenessLimited", "StateWaiting"),
                    "actions.robot.robot_capabilities"),
}


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        import importlib

        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'actions.robot' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})


__all__ = ["AnswersTicks", "AppliesCommandAtOnce", "ControlLoop", "CountsSkips",
           "DescribesStream", "LoopBehaviours", "MappedRobot", "ReportsStats", "RobotInterface",
           "RobotLoop", "Stage", "StageTimes", "StalenessLimited", "StateWaiting", "TickFilter",
           "TickTimer", "TrueState", "check_robot"]
