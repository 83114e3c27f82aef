"""The phases of a walk, and what each leg does in the gait."""

from __future__ import annotations

import enum


class WalkPhase(enum.StrEnum):
    """Phases of a walk, in order."""

    STARTING = "starting"  # on four feet, the first pair unloading
    WALKING = "walking"    # stepping
    STOPPING = "stopping"  # zero velocity, the last steps, then four loaded feet
    DONE = "done"          # standing on four loaded feet


class LegState(enum.Enum):
    """What a leg does in the gait."""

    STANCE = 0     # on the ground (reloading while its bound ramps up)
    UNLOADING = 1  # on the ground, its bound ramping down to the lift-off
    SWING = 2      # on its path to the foothold
    LATE = 3       # past its touch-down time, still lowering
