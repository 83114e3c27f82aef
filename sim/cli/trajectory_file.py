"""FollowJointTrajectory goals read from YAML or JSON files (the ``go2-wbc trajectory`` format)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from actions.messages import Duration
from actions.ros_interfaces.control_msgs import FollowJointTrajectoryGoal, JointTolerance
from actions.ros_interfaces.trajectory_msgs import JointTrajectory, JointTrajectoryPoint
from wbc.core.errors import ConfigurationError

#: The file format, as ``go2-wbc trajectory --help`` shows it.
TRAJECTORY_FORMAT_HELP = """\
trajectory file (YAML, or JSON with a .json suffix; same keys):
  joint_names: [FR_hip_joint, FR_thigh_joint, FR_calf_joint]   # joints of one leg
  points:                              # in time order
    - positions: [-0.1, -0.3, -1.6]    # [rad], one per joint name: foot up, in front
      velocities: [0.0, 0.0, 0.0]      # optional [rad/s]; in every point or in none
      accelerations: [0.0, 0.0, 0.0]   # optional [rad/s^2]; in every point or in none
      time_from_start: 2.0             # [s] from the moment the leg is free
  path_tolerance:                      # optional, per joint, during the motion
    - {name: FR_thigh_joint, position: 0.2}        # [rad]; 0 = server default, -1 = none
  goal_tolerance:                      # optional, per joint, at the end
    - {name: FR_thigh_joint, position: 0.02, velocity: 0.1}   # [rad], [rad/s]
  goal_time_tolerance: 0.5             # optional [s] after the last point
A file that cannot be read or does not have this shape is a usage error (exit 2);
joint names, lengths and times are judged by the action server (a rejection is exit 3).
The progress is the trajectory time reached: 'starting' while the leg is released (the body
shifts, the foot unloads), 'following', then 'settling' past the last point's time. The goal
ends with the foot up, the leg holding where it stopped, the robot on three feet; a Stand
goal puts the foot down.

"""

_GOAL_KEYS = ("joint_names", "points", "path_tolerance", "goal_tolerance", "goal_time_tolerance")
_POINT_KEYS = ("positions", "velocities", "accelerations", "effort", "time_from_start")
_TOLERANCE_KEYS = ("name", "position", "velocity", "acceleration")


def _mapping(value: Any, where: str, keys: Sequence[str], required: Sequence[str]
             ) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ConfigurationError(f"{where}: expected a mapping with keys {', '.join(keys)}, "
                                 f"received {type(value).__name__}")
    unknown = sorted(set(value) - set(keys), key=str)  # YAML keys may be numbers
    if unknown:
        raise ConfigurationError(f"{where}: unknown key {unknown[0]!r}; valid keys: "
                                 f"{', '.join(keys)}")
    missing = [k for k in required if k not in value]
    if missing:
        raise ConfigurationError(f"{where}: missing key {missing[0]!r}")
    return value


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise ConfigurationError(f"{where}: expected a list, received {type(value).__name__}")
    return value


def _seconds(value: Any, where: str) -> Duration:
    if isinstance(value, dict):
        return Duration(**_mapping(value, where, ("sec", "nanosec"), ()))
    return Duration.coerce(value, where)


def load_trajectory_goal(path: Path) -> FollowJointTrajectoryGoal:
    """Build a FollowJointTrajectory goal from a YAML or JSON file.

    The format is in ``go2-wbc trajectory --help``.

    Raises:
        OSError: The file cannot be read.
        ValueError: It is not valid YAML/JSON.
        ConfigurationError: It does not have the expected keys and types.
    """
    text = path.read_text(encoding="utf-8")
    if path.suffix.lower() == ".json":
        data = json.loads(text)
    else:
        import yaml

        try:
            data = yaml.safe_load(text)
        except yaml.MarkedYAMLError as err:
            mark = err.problem_mark
            where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else "?"
            raise ValueError(f"YAML error at {where}: {err.problem}") from None
        except yaml.YAMLError as err:
            raise ValueError(f"YAML error: {err}") from None
    data = _mapping(data, "file", _GOAL_KEYS, ("joint_names", "points"))
    points = []
    for i, raw in enumerate(_list(data["points"], "points")):
        where = f"points[{i}]"
        point = dict(_mapping(raw, where, _POINT_KEYS, ("positions", "time_from_start")))
        point["time_from_start"] = _seconds(point["time_from_start"],
                                            f"{where}.time_from_start")
        try:
            points.append(JointTrajectoryPoint(**point))
        except ConfigurationError as err:
            raise ConfigurationError(f"{where}: {err}") from None
    tolerances = {}
    for key in ("path_tolerance", "goal_tolerance"):
        tolerances[key] = [
            JointTolerance(**_mapping(t, f"{key}[{i}]", _TOLERANCE_KEYS, ("name",)))
            for i, t in enumerate(_list(data.get(key, []), key))
        ]
    return FollowJointTrajectoryGoal(
        trajectory=JointTrajectory(joint_names=data["joint_names"], points=points),
        goal_time_tolerance=_seconds(data.get("goal_time_tolerance", 0.0),
                                     "goal_time_tolerance"),
        **tolerances,
    )
