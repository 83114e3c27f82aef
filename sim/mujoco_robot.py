"""A MuJoCo GO2 plant behind the :class:`actions.RobotInterface`, in its actuators' order."""

from __future__ import annotations

import numpy as np

from sim.simulator import Go2Simulator
from wbc.errors import ConfigurationError
from wbc.motor_command import MotorCommand
from wbc.validation import as_float


class MujocoRobot:
    """The simulated robot as a real one would present itself: its own joint order.

    Its joint order is the plant's actuator order (the Unitree SDK's FR, FL, RR, RL when the
    plant is built that way); :class:`actions.MappedRobot` wires it to the description by
    name. Writing torques advances the simulation by one control period.

    Args:
        sim: The plant.
        control_period_s: Simulated time [s] one torque command lasts (a multiple of the
            physics timestep).
    """

    def __init__(self, sim: Go2Simulator, *, control_period_s: float = 1e-3):
        self.sim = sim
        self.substeps = max(1, round(control_period_s / sim.timestep_s))
        self._order = sim.actuator_map.index  # actuator i drives description joint index[i]
        self._reorder = not np.array_equal(self._order, np.arange(len(self._order)))

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in actuator order."""
        return self.sim.actuator_map.other_names

    @property
    def time_s(self) -> float:
        """Simulated time [s]."""
        return self.sim.time_s

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, v)``, Pinocchio convention, joints in actuator order."""
        q, v = self.sim.state()
        if self._reorder:
            q[7:] = q[7:][self._order]
            v[6:] = v[6:][self._order]
        return q, v

    def write_command(self, command: MotorCommand) -> None:
        """A motor command in actuator order; advances one control period."""
        self.sim.step_actuator_command(command, self.substeps)


def physics_steps_per_period(control_period_s: float, timestep_s: float) -> int:
    """How many physics steps of ``timestep_s`` [s] make one control period [s].

    Raises:
        ConfigurationError: The period is not a whole number (at least one) of steps.
    """
    period = as_float("control_period_s", control_period_s, low=0.0, high=0.1,
                      low_inclusive=False)
    steps = round(period / timestep_s)
    if steps < 1 or abs(steps * timestep_s - period) > 1e-9:
        raise ConfigurationError(
            f"control_period_s: expected a whole number of physics steps of {timestep_s:g} s "
            f"(e.g. {timestep_s:g}, {2 * timestep_s:g}, {4 * timestep_s:g} s), received "
            f"{period:g} s")
    return int(steps)
