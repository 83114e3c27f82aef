"""A MuJoCo GO2 behind the :class:`actions.RobotInterface`: its sensors, its actuators' order."""

from __future__ import annotations

import numpy as np

from sim.sensors import DEFAULT_SENSORS, SensorModel, SimulatedSensors
from sim.simulator import Go2Simulator
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.model.orders import Orders
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord


class MujocoRobot:
    """The simulated robot as a real one would present itself: its own joint order, sensors.

    Its joint order is the plant's actuator order (the Unitree SDK's FR, FL, RR, RL when the
    plant is built that way), and its feet come in the order its legs first appear in it;
    :class:`actions.MappedRobot` wires both to the description by name. Each
    :meth:`read_sensors` samples the simulated sensors once (one control period); writing a
    command advances the simulation by one control period, its arrays read before the write
    returns (it is also :meth:`apply_command`). :meth:`read_state` is the exact
    state, which only a simulator has (metrics, tests, ``--state truth``).

    Args:
        sim: The plant.
        control_period_s: Simulated time [s] one command lasts (a multiple of the physics
            timestep).
        sensors: The sensor model: a :class:`sim.sensors.SensorModel` or a preset name
            (default ``go2``: noise, biases, an attitude filter; ``exact``: the truth).
        sensor_seed: Seed of the sensors' noise and biases.
    """

    def __init__(self, sim: Go2Simulator, *, control_period_s: float = 1e-3,
                 sensors: SensorModel | str = DEFAULT_SENSORS, sensor_seed: int = 0):
        self.sim = sim
        self.substeps = max(1, round(control_period_s / sim.timestep_s))
        self._order = sim.actuator_map.index  # actuator i drives description joint index[i]
        self._reorder = not np.array_equal(self._order, np.arange(len(self._order)))
        legs = dict.fromkeys(name.split("_")[0] for name in self.joint_names)
        self.sensors = SimulatedSensors(sim, sensors, seed=sensor_seed, leg_order=tuple(legs))
        #: The orders of its records and commands (the actuators', the feet's).
        self.orders = Orders.of(self.joint_names, self.leg_names, name="the plant's actuator")
        self._record = SensorRecord.zeros(self.orders)
        self.sensors.prepare(self._record)  # its one compiled call loaded here, not in a tick

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in actuator order."""
        return self.sim.actuator_map.other_names

    @property
    def leg_names(self) -> tuple[str, ...]:
        """The feet's order in the sensor record."""
        return self.sensors.leg_order

    @property
    def time_s(self) -> float:
        """Simulated time [s]."""
        return self.sim.time_s

    def read_sensors(self) -> SensorRecord:
        """One sample of the simulated sensors, in the robot's orders (this robot's buffer)."""
        self.sensors.sample(self._record)
        return self._record

    def read_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The exact ``(q, v)``, Pinocchio convention, joints in actuator order."""
        q, v = self.sim.state()
        if self._reorder:
            q[7:] = q[7:][self._order]
            v[6:] = v[6:][self._order]
        return q, v

    def write_command(self, command: MotorCommand) -> None:
        """A motor command in actuator order; advances one control period.

        Raises:
            OrderMismatchError: ``command`` in another joint order than the actuators'.
        """
        if command.orders is not self.orders:
            command.orders.check(self.orders, what="MujocoRobot.write_command(command)",
                                 legs=False, fix="send it through MappedRobot (a ControlLoop "
                                 "does), which maps the controller's command by name")
        self.sim.step_actuator_command(command, self.substeps)

    #: The drivers read the command's arrays before the step returns and keep nothing of
    #: it (:class:`actions.robot.robot_capabilities.AppliesCommandAtOnce`): a loop hands it
    #: the controller's command without a copy.
    apply_command = write_command


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
