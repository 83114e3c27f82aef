"""Walking on velocity commands: a periodic gait, swing paths, footholds, the motion."""

from wbc.locomotion.foothold_planner import FootholdPlanner
from wbc.locomotion.gait import GaitClock, GaitParameters, VelocityLimits
from wbc.locomotion.swing_trajectory import swing_reference
from wbc.locomotion.walking import Walking, WalkPhase

__all__ = [
           "FootholdPlanner",
           "GaitClock",
           "GaitParameters",
           "VelocityLimits",
           "WalkPhase",
           "Walking",
           "swing_reference",
]
