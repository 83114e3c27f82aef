"""The simulated GO2 speaking the robot's DDS topics, as unitree_mujoco does: :class:`DdsBridge`.

A controller written for a real GO2 (``rt/lowstate`` in, ``rt/lowcmd`` out) runs against
the MuJoCo GO2 unchanged::

    bridge = DdsBridge(BridgeConfig(domain_id=1, interface="lo", rate_hz=500))
    bridge.run(duration_s=10.0)        # or: start(), step() ... , close()
    bridge.close()

The wire, as the robot has it (its topics, QoS, reader and writers: the robot's end of the pair,
:class:`wbc.robot_io.dds.robot_end.RobotEnd`):

- ``rt/lowstate`` (``LowState_``) at ``rate_hz`` from the simulated sensors
  (:class:`sim.sensors.SimulatedSensors`: noise, biases, the IMU's attitude filter), never
  the exact state: ``imu_state`` quaternion ``(w, x, y, z)``, gyroscope, accelerometer,
  ``rpy``; ``motor_state[0..11]`` ``q``, ``dq``, ``tau_est`` in the SDK's order (FR, FL,
  RR, RL); ``foot_force`` counts; ``tick`` +1 a message (from 1); the CRC. Header:
  ``head = FE EF``; ``level_flag = 0xFF`` (the SDK's LOWLEVEL: the bridge always takes
  low-level commands); ``motor_state[k].mode = 0x01`` for the 12 leg motors (their drivers
  are on, running the stand PD, the command or the damping) and 0x00 for slots 12 to 19.
  Writer: Reliable (100 ms max blocking) KeepLast 1, unitree_sdk2's.
- ``rt/lowcmd`` (``LowCmd_``): read BestEffort like unitree_sdk2's readers. Every physics
  step (1 kHz) takes whatever is pending, without blocking, and applies the newest command
  if it is valid, as a robot whose KeepLast 1 reader holds only the newest would. The reader
  keeps :data:`sim.command_intake.COMMAND_HISTORY` samples, so that a command overtaken by
  a newer within the same step is counted as superseded, not lost. A command with a bad
  ``head``, ``level_flag`` or CRC, or motor values a driver refuses, is dropped and counted
  by reason (:mod:`sim.bridge_stats`), as are commands pending when the bridge closes.
  Slots 0 to 11 are mapped to the plant's motors by joint name; the plant's actuators are in
  the SDK's order, as the messages are. What the drivers apply, before the first command
  and when commands stop, is :class:`sim.command_slot.CommandSlot`'s.
- ``rt/wbc/sim/truth`` (:class:`wbc.robot_io.dds.sim_truth.SimTruth`): the exact state, one
  sample per ``LowState_`` with its tick (or the bridge's count), for evaluation only.
- ``config.framing`` other than ``go2``: states framed, and commands applied, as Unitree's
  C++ or Python simulator does (:mod:`sim.state_framing`): test peers of the project's own.

Pacing: physics step ``k`` starts at ``start + k * dt`` on the clock (deadlines from the
start: no drift); until then the loop waits on the command reader, taking each command the
moment it arrives (stamped: the "received" latency). Behind by more than
:data:`MAX_LAG_STEPS` steps, it counts an overrun and starts the deadlines again from now
instead of running the missed steps in a burst. A state is written at the start of its
step, before the physics advances, so it leaves on time; its reply is applied from the
first step after it arrived.
Latency: ``LowCmd_.reserve`` echoes the ``tick`` a command answers (:mod:`sim.bridge_stats`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import asdict
from typing import Any

import numpy as np

from actions.robot.idle_collector import IdleCollector
from sim.bridge_config import BridgeConfig
from sim.bridge_stats import BridgeStats
from sim.command_intake import COMMAND_HISTORY, CommandIntake
from sim.command_slot import COMMAND, DAMPING, DAMPING_KD, STAND_KD, STAND_KP, CommandSlot
from sim.sensors import SimulatedSensors
from sim.sim_truth import sim_truth_record
from sim.simulator import Go2Simulator
from sim.state_framing import UNITREE_PYTHON, StateFraming, StateGaps
from sim.truth_log import TruthLog
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float
from wbc.model.description import LEGS, UNITREE_SDK_JOINT_NAMES
from wbc.robot_io.dds.c_layout import LOW_STATE_DTYPE, zero_record
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.low_state_conversion import low_state_from_sensor_record
from wbc.robot_io.dds.robot_end import RobotEnd
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC, SimTruthMessage
from wbc.robot_io.dds.wire_message import LowStateMessage
from wbc.robot_io.sensor_record import SensorRecord

#: Physics steps the loop may fall behind the clock before it resynchronises (an overrun).
MAX_LAG_STEPS = 3
#: What each mode change says (:attr:`DdsBridge.on_event`).
_TRANSITIONS = {
    ("stand", COMMAND): "first valid command: the controller drives the motors",
    (COMMAND, DAMPING): "no valid command for {timeout:g} s: motors damping (kp 0, kd {kd:g})",
    (DAMPING, COMMAND): "commands resumed: the controller drives the motors again",
}


class DdsBridge:
    """A MuJoCo GO2 behind ``rt/lowstate`` / ``rt/lowcmd`` (see the module docstring).

    Use :meth:`run` (paced to the clock, until :meth:`stop` or a duration), or :meth:`start`
    then :meth:`step` as often as wanted (unpaced: a test drives it), and :meth:`close` in
    every case (also a context manager). :meth:`stop` and :meth:`close` may be called from
    another thread than the loop's.

    Args:
        config: The domain, rates, plant, sensors and command handling.
        clock: The clock [s] for pacing, timeouts and latencies (``time.monotonic``).
        sleep: Waits a number of seconds between steps; ``None`` (the default): wait on the
            command reader, taking each command as it arrives (stamped with ``clock``:
            :meth:`sim.command_intake.CommandIntake.wait_until`).
        on_event: Told ``(sim time [s], text)`` of each mode change, the first rejected
            command of each reason and the viewer's closing; called on the loop's thread.

    Raises:
        ConfigurationError: The plant's actuators cannot be wired to the SDK's slots.
    """

    def __init__(self, config: BridgeConfig | None = None, *,
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] | None = None,
                 on_event: Callable[[float, str], None] | None = None):
        self.config = config = config or BridgeConfig()
        self._clock, self._sleep = clock, sleep
        self.on_event = on_event
        #: The plant, its actuators in the SDK's motor order.
        self.sim = Go2Simulator(timestep_s=config.physics_timestep_s,
                                actuator_order=UNITREE_SDK_JOINT_NAMES,
                                plant=config.plant_model)
        self.sim.reset(config.pose)
        self._joint_names = self.sim.actuator_map.other_names
        self._to_plant = self.sim.actuator_map.index  # description -> plant order, by name
        self._to_description = self.sim.actuator_map.inverse
        #: The SDK motor slot of each plant actuator, by joint name.
        self._slots = np.array([UNITREE_SDK_JOINT_NAMES.index(name)
                                for name in self._joint_names], dtype=np.intp)
        self._sensors = SimulatedSensors(self.sim, config.sensor_model, seed=config.sensor_seed,
                                         leg_order=LEGS)
        pose_q = self.sim.description.pose(config.pose)[7:]
        #: How states are framed and commands applied (:mod:`sim.state_framing`).
        self.framing = framing = StateFraming(config.framing)
        #: The gaps of Unitree's Python simulator's stream (``None`` for other framings).
        self.gaps = StateGaps(config.sensor_seed) if framing.name == UNITREE_PYTHON else None
        #: What the drivers apply: stand (no torque for Unitree's simulators), the newest
        #: command, or damping (never for Unitree's simulators: they hold the last command).
        self.slot = CommandSlot(None if framing.unitree else pose_q[self._to_plant],
                                timeout_s=None if framing.unitree else config.command_timeout_s,
                                delay_steps=config.delay_steps)
        self.stats = BridgeStats()
        #: Python's garbage collection, between physics steps while :meth:`run` runs.
        self.collector = IdleCollector()
        #: Every truth sample published, when ``config.log_truth``.
        self.truth_log = TruthLog() if config.log_truth else None
        #: Physics steps done; ``LowState_`` ticks published (the last tick).
        self.steps = 0
        self.tick = 0
        #: Wall time [s] spent in :meth:`run`.
        self.wall_s = 0.0
        self._raw = SensorRecord.zeros()  # plant joint order, description leg order
        self._sensor = SensorRecord.zeros()  # description orders
        self._state = zero_record(LOW_STATE_DTYPE)
        framing.header(self._state)
        self._state_message = LowStateMessage(self._state)
        self._truth_message = SimTruthMessage()
        self._rejected_reasons: set[str] = set()
        self._wire: RobotEnd | None = None
        self._view: Any = None
        self._stop = threading.Event()
        self._closed = False
        self._lock = threading.RLock()  # held by the loop; close() waits for it

    # ------------------------------------------------------------------ life cycle

    @property
    def mode(self) -> str:
        """What the drivers apply now: ``stand``, ``command`` or ``damping``."""
        return self.slot.mode

    @property
    def is_started(self) -> bool:
        """Whether :meth:`start` was called and :meth:`close` was not."""
        return self._wire is not None

    def start(self) -> None:
        """Join the domain, make the writers and the reader, open the viewer; idempotent.

        Raises:
            ConfigurationError: The domain cannot be joined (configured otherwise in this
                process, refused by Cyclone) or the bridge is closed.
        """
        with self._lock:
            if self._wire is not None:
                return
            if self._closed:
                raise ConfigurationError("start: the bridge is closed; make a new one")
            # unitree_sdk2's channels; the command reader keeps a few, to count every
            # command (the module docstring).
            self._wire = RobotEnd(domain_id=self.config.domain_id,
                                  interface=self.config.interface,
                                  command_depth=COMMAND_HISTORY)
            self._intake = CommandIntake(self._wire, self.stats, slots=self._slots,
                                         to_plant=self._to_plant,
                                         joint_names=self._joint_names,
                                         effort_limit=self.sim.effort_limit,
                                         reject=self._reject)
            if self.config.viewer:
                self._open_viewer()

    def stop(self) -> None:
        """Make :meth:`run` return after its current step (any thread, a signal handler)."""
        self._stop.set()

    def close(self) -> None:
        """Stop the loop, close the viewer, count the commands still pending (never applied),
        delete the readers, writers and participant; idempotent. From another thread, waits
        for the loop's current step."""
        self._stop.set()
        with self._lock:
            self._closed = True
            view, self._view = self._view, None
            if view is not None:
                view.close()
            wire, self._wire = self._wire, None
            if wire is not None:
                self._intake.count_pending()
                wire.close()

    def __enter__(self) -> DdsBridge:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ the loop

    def run(self, duration_s: float | None = None) -> BridgeStats:
        """Step in time with the clock until :meth:`stop` (at once if it was called before)
        or until ``duration_s`` [s] have passed (``None``: until stopped); :meth:`start` first
        if needed. Does not close.

        Raises:
            ConfigurationError: A negative or non-finite duration; see :meth:`start`.
        """
        length_s = None if duration_s is None else as_float("duration_s", duration_s, low=0.0)
        # Python's garbage collection between steps only (IdleCollector).
        with self._lock, self.collector:
            self.start()
            clock, dt = self._clock, self.config.physics_timestep_s
            start_s = clock()
            end_s = None if length_s is None else start_s + length_s
            base_s, base_step = start_s, self.steps
            try:
                while not self._stop.is_set():
                    deadline = base_s + (self.steps - base_step) * dt
                    if end_s is not None and deadline >= end_s - 1e-9:
                        break
                    now = clock()
                    if now < deadline:
                        if self._sleep is None:
                            self._intake.wait_until(deadline, clock)
                        else:
                            self._sleep(deadline - now)
                    elif now - deadline > MAX_LAG_STEPS * dt:
                        self.stats.overruns += 1
                        base_s, base_step = now, self.steps
                    self.step()
                    self.collector.collect(deadline + dt - clock())
            finally:
                self.wall_s += clock() - start_s
        return self.stats

    def step(self) -> None:
        """One physics step: publish the state if one is due, take the newest valid command,
        apply what the drivers apply (:class:`CommandSlot`), advance the physics.

        Raises:
            ConfigurationError: Not started (or closed).
            NonFiniteError: The simulation diverged.
        """
        with self._lock:
            wire = self._wire
            if wire is None:
                raise ConfigurationError("step: the bridge is not started (start() it first) "
                                         "or is closed")
            if self.steps % self.config.steps_per_state == 0:
                self._publish(wire)
            now = self._clock()
            newest = self.framing.applied(self._intake.take(now), self.sim)
            command = self.slot.step(newest, now_s=now)
            stats, slot = self.stats, self.slot
            stats.commands_applied, stats.timeouts = slot.applied, slot.timeouts
            stats.commands_in_flight = slot.in_flight
            if slot.transition is not None:  # every change the slot makes is listed
                self._event(_TRANSITIONS[slot.transition].format(timeout=slot.timeout_s,
                                                                 kd=DAMPING_KD))
            if self.gaps is None or not self.gaps.physics_halted:
                self.sim.step_actuator_command(command)
            self.steps += 1
            if self._view is not None:  # no overlay: the hook reads neither argument
                self._view(None, None)

    # ------------------------------------------------------------------ inside

    def _publish(self, wire: RobotEnd) -> None:
        """Sample the sensors, write ``LowState_``, then the truth (in a gap: see StateGaps)."""
        gap = "" if self.gaps is None else self.gaps.at_state(
            self.steps * self.config.physics_timestep_s)
        if gap:
            if gap == "frozen":
                wire.write_state(self._state_message)
            return
        self.tick += 1
        raw, sensor = self._raw, self._sensor
        self._sensors.sample(raw)
        back = self._to_description  # plant joint order -> description order, by name
        np.take(raw.q, back, out=sensor.q)
        np.take(raw.dq, back, out=sensor.dq)
        np.take(raw.tau_est, back, out=sensor.tau_est)
        sensor.imu_quaternion_wxyz[:] = raw.imu_quaternion_wxyz
        sensor.gyroscope_rad_s[:] = raw.gyroscope_rad_s
        sensor.accelerometer_m_s2[:] = raw.accelerometer_m_s2
        sensor.foot_force[:] = raw.foot_force
        sensor.stamp_s, sensor.tick = raw.stamp_s, self.tick
        low_state_from_sensor_record(sensor, out=self._state)  # SDK orders, CRC
        self.framing.frame(self._state, sim_time_s=self.sim.time_s)
        # Stamped before the write: a reply can arrive while write() is still returning.
        written_s, written_ns = self._clock(), time.time_ns()
        wire.write_state(self._state_message)
        tick = self.framing.state_tick(self._state, self.tick)  # what a reply echoes
        self.stats.published(tick, written_s, written_ns)
        truth = sim_truth_record(self.sim, tick, out=self._truth_message.record)
        wire.write_truth(self._truth_message)
        if self.truth_log is not None:
            self.truth_log.append(truth)

    def _reject(self, reason: str, message: str) -> None:
        self.stats.rejected(reason, message)
        if reason not in self._rejected_reasons:  # the first of each reason only
            self._rejected_reasons.add(reason)
            self._event(f"dropped a LowCmd_ ({reason}; the first, counted from now on): "
                        f"{message}")

    def _event(self, text: str) -> None:
        if self.on_event is not None:
            self.on_event(self.sim.time_s, text)

    def _open_viewer(self) -> None:
        from sim.viewer import ViewerHook, window_problem

        problem = window_problem()
        if problem:
            self._event(f"--viewer: {problem}; running headless")
            return
        try:
            self._view = ViewerHook(self.sim, on_closed=lambda: self._event(
                "viewer: the window was closed; the bridge goes on headless"))
        except Exception as err:  # noqa: BLE001 - GLFW and X fail in assorted types
            self._event(f"--viewer: cannot open a window ({' '.join(str(err).split())}); "
                        "running headless")

    # ------------------------------------------------------------------ report

    def report(self) -> dict[str, Any]:
        """The configuration, the run's times and :class:`BridgeStats`, JSON-ready."""
        config = self.config
        return {
            "domain_id": config.domain_id, "interface": config.interface,
            "topics": {"state": LOW_STATE_TOPIC, "command": LOW_CMD_TOPIC,
                       "truth": SIM_TRUTH_TOPIC},
            "rate_hz": config.rate_hz, "physics_timestep_s": config.physics_timestep_s,
            "plant": asdict(config.plant_model), "sensors": config.sensor_model.as_dict(),
            "sensor_seed": config.sensor_seed, "pose": config.pose,
            "command_delay_s": config.command_delay_s,
            "command_timeout_s": config.command_timeout_s,
            "stand_kp": STAND_KP, "stand_kd": STAND_KD, "damping_kd": DAMPING_KD,
            "framing": config.framing,
            "gaps": None if self.gaps is None else self.gaps.report(),
            "steps": self.steps, "sim_time_s": self.sim.time_s, "wall_time_s": self.wall_s,
            "final_mode": self.mode, "stats": self.stats.as_dict(),
            "gc": self.collector.report(),
        }

