"""The controller of a robot on DDS: DdsRobot against an in-process publisher, the wall-clock
loop's deadlines on an injected clock, the staleness watchdog, the stop path, the command line,
and a high five over DDS against the simulator bridge in a subprocess."""

from __future__ import annotations

import gc
import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic

from actions.go2.go2_interfaces import HIGH_FIVE, HighFiveGoal
from actions.goal_status import GoalStatus
from actions.robot import dds_robot as dds_robot_module
from actions.robot.control_loop import ControlLoop
from actions.robot.dds_robot import DdsRobot, DdsRobotCounters, NoRobotStateError
from actions.robot.deadline_clock import DeadlineClock
from actions.robot.realtime_loop import (
    ALIGN_FOLLOW_S,
    ALIGN_STEP_S,
    RealtimeLoop,
    stop_on_signals,
)
from actions.robot.rest_sequence import Phase
from actions.robot.robot_interface import RobotWrapper
from actions.robot.state_fallback import LoopMode
from actions.robot.tick_log import TickLog
from actions.robot.tick_stats import SERIES
from sim.control_loop import ControlLoop as SimLoop
from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from wbc.controller.control_output import ControlStatus
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.model.description import JOINT_NAMES, UNITREE_SDK_JOINT_NAMES
from wbc.robot_io.dds.domain_config import delete_entities, join_domain
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.low_cmd_conversion import low_cmd_fault
from wbc.robot_io.dds.low_state_conversion import low_state_from_sensor_record
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.sensor_record import SensorRecord

ROOT = Path(__file__).resolve().parents[1]
#: Private domains on loopback: one for the in-process tests, one for the bridge's.
DOMAIN = 210 + os.getpid() % 20
BRIDGE_DOMAIN = 210 + (os.getpid() + 10) % 20
PERIOD_S = 0.002
#: Longest wall-clock wait for anything that takes milliseconds [s].
WAIT_S = 10.0


def wait_until(condition: Callable[[], bool], what: str, timeout_s: float = WAIT_S) -> None:
    """Poll ``condition`` every millisecond for at most ``timeout_s`` [s, wall clock]."""
    end = time.monotonic() + timeout_s
    pause = threading.Event()
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        pause.wait(0.001)


# --------------------------------------------------------------------------- DdsRobot


def standing_record(tick: int) -> SensorRecord:
    """A sample with distinct joint values (description order) and the given tick."""
    record = SensorRecord.zeros()
    record.tick = tick
    record.accelerometer_m_s2[:] = (0.0, 0.0, 9.81)
    record.q[:] = np.linspace(-1.0, 1.0, 12)
    record.dq[:] = np.linspace(0.1, 1.2, 12)
    record.foot_force[:] = (10.0, 20.0, 30.0, 40.0)
    return record


class FakeGo2:
    """The robot's side of the wire in this process: a ``LowState_`` writer, a ``LowCmd_``
    reader."""

    def __init__(self) -> None:
        self.dds = join_domain("lo", domain_id=DOMAIN)
        participant = self.dds.participant
        best_effort = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(1))
        self.writer = DataWriter(participant, Topic(participant, LOW_STATE_TOPIC,
                                                    LowStateMessage), qos=best_effort)
        self.reader = DataReader(participant, Topic(participant, LOW_CMD_TOPIC, LowCmdMessage),
                                 qos=Qos(Policy.Reliability.Reliable(0),
                                         Policy.History.KeepLast(1)))

    def publish(self, tick: int, *, corrupt: str = "") -> None:
        record = low_state_from_sensor_record(standing_record(tick))
        if corrupt == "crc":
            record["crc"] ^= 1
        elif corrupt == "head":
            record["head"][0] = 0
        self.writer.write(LowStateMessage(record))

    def commands(self) -> list[np.ndarray]:
        return [m.record for m in self.reader.take(16) if m.sample_info.valid_data]

    def close(self) -> None:
        delete_entities(self.reader, self.writer)
        self.dds.close()


@pytest.fixture
def go2() -> Iterator[FakeGo2]:
    fake = FakeGo2()
    try:
        yield fake
    finally:
        fake.close()


@pytest.fixture
def robot() -> Iterator[DdsRobot]:
    dds_robot = DdsRobot(domain_id=DOMAIN, interface="lo")
    try:
        yield dds_robot
    finally:
        dds_robot.close()


def matched(go2: FakeGo2, robot: DdsRobot) -> None:
    wait_until(lambda: go2.writer.get_publication_matched_status().current_count > 0
               and (robot.dry_run or go2.reader.get_subscription_matched_status()
                    .current_count > 0), "the fake GO2 and the robot to match")


def command(kp: float = 20.0) -> MotorCommand:
    """A description-order command whose values tell the joints apart."""
    joints = np.arange(12.0)
    return MotorCommand(q_des=0.1 * joints, dq_des=np.zeros(12), kp=np.full(12, kp),
                        kd=np.full(12, 1.0), tau_ff=joints - 6.0)


def test_reads_the_newest_state_once_and_counts_the_ticks_it_skipped(go2, robot):
    matched(go2, robot)
    assert robot.read_sensors() is None
    go2.publish(1)
    first = robot.read_sensors()
    assert first is not None and first.tick == 1
    for tick in (2, 3, 4, 5):  # KeepLast 1: only 5 is held when the robot reads
        go2.publish(tick)
    before = robot.time_s
    newest = robot.read_sensors()
    assert newest is not None and newest.tick == 5
    assert before <= newest.stamp_s <= robot.time_s  # taken now, on the robot's clock
    np.testing.assert_allclose(newest.q, standing_record(5).q, atol=1e-6)  # mapped by name
    np.testing.assert_allclose(newest.foot_force, (10, 20, 30, 40))
    assert robot.read_sensors() is None  # nothing new: never the same state twice
    counters = robot.counters
    assert (counters.states_used, counters.ticks_skipped, counters.no_new_state) == (2, 3, 2)


@pytest.mark.parametrize("corrupt, field", [("crc", "LowState_.crc"),
                                            ("head", "LowState_.head")])
def test_drops_a_state_with_a_bad_crc_or_head(go2, robot, corrupt, field):
    matched(go2, robot)
    go2.publish(7, corrupt=corrupt)
    assert robot.read_sensors() is None
    assert robot.counters.bad_frames == 1 and robot.counters.states_used == 0
    assert robot.last_fault.startswith(field)
    go2.publish(8)
    assert robot.read_sensors().tick == 8


def received_commands(go2: FakeGo2, count: int = 1) -> list[np.ndarray]:
    """The commands the fake GO2 received, waiting until there are ``count``."""
    received: list[np.ndarray] = []
    wait_until(lambda: received.extend(go2.commands()) or len(received) >= count,
               f"{count} command(s)")
    return received


def test_a_command_echoes_the_tick_it_answers_in_reserve_with_a_valid_crc(go2, robot):
    matched(go2, robot)
    go2.publish(41)
    robot.read_sensors()
    robot.write_command(command())
    (record,) = received_commands(go2)
    assert int(record["reserve"]) == 41
    assert low_cmd_fault(record) is None  # head, level_flag and CRC as the robot checks them
    slots = record["motor_cmd"]
    for slot, name in enumerate(UNITREE_SDK_JOINT_NAMES):  # SDK order, by joint name
        j = JOINT_NAMES.index(name)
        assert slots["tau"][slot] == pytest.approx(j - 6.0)
        assert slots["q"][slot] == pytest.approx(0.1 * j)
    assert robot.counters.commands_sent == 1


def test_a_command_it_cannot_carry_is_refused_not_published(go2, robot):
    matched(go2, robot)
    bad = command()
    bad.tau_ff[3] = np.nan
    robot.write_command(bad)
    robot.write_command(command())  # the next good one goes out
    (record,) = received_commands(go2)
    assert low_cmd_fault(record) is None
    assert record["motor_cmd"]["tau"][:12].tolist() == pytest.approx(
        [JOINT_NAMES.index(name) - 6.0 for name in UNITREE_SDK_JOINT_NAMES])
    assert robot.counters.commands_refused == 1 and robot.counters.commands_sent == 1
    assert "tau" in robot.last_fault


def test_commands_written_before_the_robots_reader_matched_are_counted_apart(robot):
    robot.write_command(command())  # nobody reads rt/lowcmd yet: it goes nowhere
    assert (robot.counters.commands_sent, robot.counters.commands_unmatched) == (1, 1)
    fake = FakeGo2()
    try:
        matched(fake, robot)
        robot.write_command(command())
        assert (robot.counters.commands_sent, robot.counters.commands_unmatched) == (2, 1)
        assert len(received_commands(fake)) == 1
    finally:
        fake.close()


def test_the_first_state_wait_logs_a_robot_without_a_command_reader(robot, monkeypatch,
                                                                    caplog):
    monkeypatch.setattr(dds_robot_module, "MATCH_WAIT_S", 0.05)
    dds = join_domain("lo", domain_id=DOMAIN)
    participant = dds.participant
    writer = DataWriter(participant, Topic(participant, LOW_STATE_TOPIC, LowStateMessage))
    try:
        wait_until(lambda: writer.get_publication_matched_status().current_count > 0,
                   "the state writer to match")
        writer.write(LowStateMessage(low_state_from_sensor_record(standing_record(5))))
        assert robot.wait_for_first_state(WAIT_S).tick == 5
    finally:
        delete_entities(writer)
        dds.close()
    assert f"no reader of {LOW_CMD_TOPIC} matched 0.05 s after the first state" in caplog.text


def test_dry_run_publishes_nothing_and_keeps_the_command(go2):
    dry = DdsRobot(domain_id=DOMAIN, interface="lo", dry_run=True)
    try:
        matched(go2, dry)
        go2.publish(3)
        dry.read_sensors()
        dry.write_command(command())
        assert go2.reader.get_subscription_matched_status().current_count == 0  # no writer
        assert go2.commands() == []
        assert dry.counters.commands_sent == 1
        assert int(dry.last_low_cmd["reserve"]) == 3
        assert low_cmd_fault(dry.last_low_cmd) is None
        np.testing.assert_allclose(dry.last_command.to_motor_command().tau_ff,
                                   command().tau_ff)
    finally:
        dry.close()


def test_waiting_for_a_robot_that_does_not_publish_names_topic_domain_and_interface(robot):
    start = time.monotonic()
    with pytest.raises(NoRobotStateError) as caught:
        robot.wait_for_first_state(0.2)
    assert time.monotonic() - start < 2.0
    text = str(caught.value)
    assert f"rt/lowstate within 0.2 s (DDS domain {DOMAIN}, interface 'lo')" in text
    assert "no publisher of rt/lowstate matched" in text
    assert "Is the bridge or robot running?" in text


def test_the_first_state_waited_for_is_the_first_one_read(go2, robot):
    matched(go2, robot)
    go2.publish(12)
    assert robot.wait_for_first_state(WAIT_S).tick == 12
    assert robot.read_sensors().tick == 12
    assert robot.read_sensors() is None


# --------------------------------------------------------------------------- deadlines


class FakeClock:
    """A monotonic clock that only moves when slept on, or by hand (``advance``)."""

    def __init__(self, *, per_read_s: float = 0.0) -> None:
        self.t = 100.0
        self.per_read_s = per_read_s
        self.sleeps: list[float] = []

    def __call__(self) -> float:
        self.t += self.per_read_s
        return self.t

    def sleep(self, seconds: float) -> None:
        assert seconds > 0.0
        self.sleeps.append(seconds)
        self.t += seconds

    def advance(self, seconds: float) -> None:
        self.t += seconds


def test_a_missed_deadline_is_counted_and_never_made_up_in_a_burst():
    clock = FakeClock()
    deadlines = DeadlineClock(PERIOD_S, clock=clock, sleep=clock.sleep, spin_s=0.0)
    deadlines.start()
    t0, starts, missed, left = clock.t, [], [], []
    for work_ms in (0.5, 0.5, 3.0, 0.5, 5.0, 0.5, 0.5):
        assert deadlines.wait() == 0.0
        starts.append(round((clock.t - t0) * 1e3, 9))
        clock.advance(work_ms * 1e-3)
        left.append(round(deadlines.time_left_s() * 1e3, 9))
        missed.append(deadlines.tick_done())
    # The time left in each tick's period, negative when it overran.
    assert left == [1.5, 1.5, -1.0, 1.5, -3.0, 1.5, 1.5]
    # 4 + 3 ms overran 6: the next tick starts at once (7), then every 2 ms from there.
    assert starts == [0.0, 2.0, 4.0, 7.0, 9.0, 14.0, 16.0]
    assert missed == [False, False, True, False, True, False, False]
    assert (deadlines.misses, deadlines.ticks) == (2, 7)


def test_it_sleeps_until_the_spin_then_spins_onto_the_deadline():
    clock = FakeClock(per_read_s=1e-6)  # every read of the clock takes 1 us
    deadlines = DeadlineClock(PERIOD_S, clock=clock, sleep=clock.sleep, spin_s=2e-4)
    deadlines.start()
    deadlines.tick_done()
    late = deadlines.wait()
    assert 0.0 <= late <= 2e-6
    assert clock.sleeps and clock.sleeps[-1] == pytest.approx(PERIOD_S - 2e-4, abs=5e-6)


# --------------------------------------------------------------------------- the wall-clock loop


class TestRobot(RobotWrapper):
    """A simulated GO2 whose states can stop, on the fake wall clock when one is given."""

    __test__ = False

    def __init__(self, robot: MujocoRobot, clock: FakeClock | None = None) -> None:
        super().__init__(robot)
        self.clock = clock
        self._t0 = 0.0 if clock is None else clock.t
        self.dropping = False
        self.last_command: MotorCommand | None = None

    @property
    def time_s(self) -> float:
        return self.robot.time_s if self.clock is None else self.clock.t - self._t0

    def read_sensors(self) -> SensorRecord | None:
        return None if self.dropping else self.robot.read_sensors()

    def write_command(self, command: MotorCommand) -> None:
        self.last_command = command.copy()
        self.robot.write_command(command)


def sim_loop(clock: FakeClock | None = None, pose: str = "standing"
             ) -> tuple[ControlLoop, TestRobot, MujocoRobot]:
    """A simulated GO2 in ``pose`` at 500 Hz behind a :class:`TestRobot`."""
    sim = Go2Simulator(timestep_s=1e-3)
    plant = MujocoRobot(sim, control_period_s=PERIOD_S, sensor_seed=0)
    sim.reset(pose)
    plant.sensors.reset()
    robot = TestRobot(plant, clock)
    controller = WholeBodyController(solver={"control_period_s": PERIOD_S})
    return ControlLoop(robot, controller), robot, plant


def realtime(loop: ControlLoop, clock: FakeClock, **kwargs) -> RealtimeLoop:
    return RealtimeLoop(loop, rate_hz=500, clock=clock, sleep=clock.sleep, spin_s=0.0,
                        **kwargs)


def tick_until(rt: RealtimeLoop, condition: Callable[[], bool], what: str,
               max_ticks: int = 10_000) -> int:
    for k in range(max_ticks):
        if condition():
            return k
        rt.tick()
    raise AssertionError(f"{what}: not after {max_ticks} ticks")


def test_its_staged_tick_is_the_control_loops_spin():
    reference = SimLoop.simulated(control_period_s=PERIOD_S)
    loop = SimLoop.simulated(control_period_s=PERIOD_S)
    clock = FakeClock()
    rt = realtime(loop, clock)
    for _ in range(50):
        expected = reference.spin_once()
        rt.tick()
        np.testing.assert_array_equal(rt.last_output.tau_ff, expected.tau_ff)
        np.testing.assert_array_equal(rt.last_output.q_des, expected.q_des)
    assert rt.stats.ticks == 50 and rt.stats.misses == 0 and rt.stats.no_fresh_state == 0
    summary = rt.stats.summary()
    assert set(summary) == set(SERIES)
    assert summary["controller"]["mean_ms"] > 0.0
    assert summary["tick"]["max_ms"] >= summary["latency"]["max_ms"]


def test_states_stopping_abort_the_goal_damp_and_control_resumes_after_a_stand():
    clock = FakeClock()
    loop, robot, plant = sim_loop()
    rt = realtime(loop, clock)
    future = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3,
                                                                   hold_seconds=2))
    tick_until(rt, lambda: future.done() and future.result().status == GoalStatus.EXECUTING,
               "the high five to start")
    handle = future.result()
    tick_until(rt, lambda: not loop.controller.schedule.is_stance("FR"), "the foot to lift")
    robot.dropping = True
    statuses = []
    for _ in range(15):  # 30 ms without a state
        rt.tick()
        statuses.append(rt.last_output.status)
    robot.dropping = False
    # The estimator's trust_timeout_s (10 ms) of ticks, then the fallback with the reason; the
    # goal ends ABORTED at once, with it.
    assert statuses[:5] == [ControlStatus.OK] * 5
    assert statuses[6:] == [ControlStatus.FALLBACK] * 9
    assert rt.last_output.message.startswith("state estimate: no trustworthy sensor sample")
    assert rt.stats.no_fresh_state == 15 and rt.stats.watchdog_trips == 1
    assert handle.status == GoalStatus.ABORTED
    result = handle.get_result_async().result(0).result
    assert result.message.startswith("the state stopped being trustworthy (state estimate: no "
                                     "trustworthy sensor sample")
    # States back: the estimator starts again and a stand goal stands the robot up.
    rt.tick()
    assert loop.fallback.mode is LoopMode.RECOVERING and loop.estimator.restarts == 1
    assert rt.last_output.status is ControlStatus.OK
    tick_until(rt, lambda: loop.ready, "the recovery stand to succeed", 1500)
    rt_ok = rt.stats.ticks
    for _ in range(250):  # half a second: it stays up
        rt.tick()
    assert plant.read_state()[0][2] > 0.25
    assert rt.last_output.status is ControlStatus.OK and rt.stats.ticks == rt_ok + 250


def test_the_watchdog_counts_wall_time_when_ticks_are_late():
    clock = FakeClock()
    loop, robot, _ = sim_loop(clock)
    rt = realtime(loop, clock)
    rt.callbacks.append(lambda rt: clock.advance(0.006) if robot.dropping else None)
    for _ in range(10):
        rt.tick()
    robot.dropping = True
    for _ in range(3):  # three ticks, 8 ms apart: 3 periods for the estimator, 24 ms of wall
        rt.tick()
    robot.dropping = False
    assert rt.stats.misses == 3 and rt.stats.watchdog_trips == 1
    assert rt.last_output.status is ControlStatus.FALLBACK
    assert rt.last_output.message == "watchdog: no fresh robot state for 14 ms (limit 10 ms)"
    assert loop.estimator.estimate.usable  # the estimator alone would not have noticed
    rt.tick()
    assert rt.last_output.status is ControlStatus.OK


def test_a_stop_unwinds_the_goal_sits_and_damps():
    clock = FakeClock()
    loop, robot, plant = sim_loop()
    rt = realtime(loop, clock)
    log = TickLog()
    rt.callbacks.append(log.record)
    future = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3,
                                                                   hold_seconds=5))
    tick_until(rt, lambda: future.done() and not loop.controller.schedule.is_stance("FR"),
               "the foot to lift")
    before = signal.getsignal(signal.SIGINT)  # the default, or SIG_IGN under nohup
    with stop_on_signals(rt):
        signal.raise_signal(signal.SIGINT)  # Ctrl-C: handled, not raised
    assert signal.getsignal(signal.SIGINT) is before  # the handler it found, restored
    tick_until(rt, lambda: rt.done, "the robot to come to rest", 5000)
    handle = future.result()
    assert handle.status == GoalStatus.CANCELED  # the foot went down first
    assert rt.rest.stop_reason == "SIGINT"
    assert rt.rest.notes == ["canceled goal 1 (high_five)", "sit ended SUCCEEDED",
                             "damping (at rest)"]
    assert plant.read_state()[0][2] < 0.15  # lying
    last = robot.last_command  # pure damping
    assert rt.last_output is None
    assert (last.kp == 0).all() and (last.tau_ff == 0).all() and (last.kd == 5.0).all()
    arrays = log.arrays(rt)
    phases = arrays["phase"]
    assert phases[0] == Phase.RUNNING and phases[-1] == Phase.DONE  # damping sent on it too
    assert set(np.unique(phases)) == set(Phase)
    assert (np.diff(phases) >= 0).all()
    assert arrays["swing"][:, 1].any() and not arrays["swing"][-1].any()
    assert np.isfinite(arrays["foot_target"][arrays["swing"][:, 1], 1]).all()
    assert np.isfinite(arrays["stage_s"]).all()
    assert len(arrays["t_s"]) == rt.stats.ticks


def test_run_collects_garbage_at_the_end_of_its_ticks_only():
    """Automatic collection is off while the loop runs (a collection would start inside any
    allocation: a QP, a write); the ticks' ``gc`` stage collects instead."""
    clock = FakeClock()
    loop, _, _ = sim_loop(clock)
    rt = realtime(loop, clock)
    during: list[bool] = []
    rt.callbacks.append(lambda _: during.append(gc.isenabled()))
    enabled, thresholds = gc.isenabled(), gc.get_threshold()
    gc.enable()
    gc.set_threshold(5, 2, 2)  # the ticks allocate little: a few tracked objects each
    try:
        rt.run(duration_s=0.2)
        assert gc.isenabled()  # as it was before
    finally:
        gc.set_threshold(*thresholds)
        (gc.enable if enabled else gc.disable)()
    assert during and not any(during)
    collections = rt.report()["gc"]["collections"]
    assert collections[0] >= 10 and collections[1] >= 1
    assert rt.stats.summary()["gc"]["max_ms"] > 0.0


def test_a_second_stop_damps_at_once():
    clock = FakeClock()
    loop, _, _ = sim_loop()
    rt = realtime(loop, clock)
    future = loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.3,
                                                                   hold_seconds=5))
    tick_until(rt, lambda: future.done() and not loop.controller.schedule.is_stance("FR"),
               "the foot to lift")
    rt.request_stop("SIGINT")
    rt.tick()
    rt.request_stop("SIGINT")
    rt.tick()
    assert rt.rest.phase is Phase.DAMPING and loop.runner.is_shut_down
    assert future.result().status == GoalStatus.ABORTED
    tick_until(rt, lambda: rt.done, "the damping to end", 400)


def test_a_robot_that_is_down_is_stood_up_first():
    clock = FakeClock()
    loop, _, plant = sim_loop(pose="lying")
    rt = realtime(loop, clock)
    assert loop.context.q[2] < 0.2
    rt.start()
    assert rt.rest.stand is not None
    handle_future = rt.rest.stand
    tick_until(rt, lambda: handle_future.done() and handle_future.result().status.is_terminal,
               "the stand to end", 3000)
    assert handle_future.result().status == GoalStatus.SUCCEEDED
    assert plant.read_state()[0][2] > 0.3
    rt.start()  # once only
    assert rt.rest.stand is handle_future


# --------------------------------------------------------------------------- command line


def go2_wbc(*argv: str) -> int:
    from sim.cli import main

    return main(list(argv))


@pytest.mark.parametrize("argv, message", [
    (("run", "--dds", "--interface", "nosuch0"), "--interface: expected one of this host's"),
    (("run", "--dds", "--domain", "233"), "--domain: expected a DDS domain id in [0, 232]"),
    (("run",), "--dds: required"),
    (("high-five", "--dds", "--plant", "ideal"), "--plant: a simulation option, not used"),
    (("high-five", "--domain", "3"), "--domain: only used with --dds"),
    (("send-goal", "high_five", "{}", "--dds", "--interface", "nosuch0"),
     "--interface: expected one of this host's"),
])
def test_bad_input_is_one_line_and_a_usage_error(capsys, argv, message):
    with pytest.raises(SystemExit) as exited:
        go2_wbc(*argv)
    assert exited.value.code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_run_without_a_robot_says_so_and_exits_unavailable(capsys):
    assert go2_wbc("run", "--dds", "--domain", str(DOMAIN), "--wait", "0.2") == 4
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Is the bridge or robot running?" in err


def test_send_goal_without_a_server_gives_the_clients_reason(capsys, monkeypatch):
    import sim.cli.dds_goal as dds_goal

    monkeypatch.setattr(dds_goal, "SERVER_WAIT_S", 0.2)
    assert go2_wbc("send-goal", "high_five", "{}", "--dds", "--domain", str(DOMAIN)) == 4
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "no action server 'high_five' (go2_interfaces/action/HighFive) matched" in err
    assert f"DDS domain {DOMAIN}" in err


# --------------------------------------------------------------------------- end to end


def run_until(rt: RealtimeLoop, condition: Callable[[], bool], what: str,
              timeout_s: float) -> None:
    """Tick ``rt`` on the wall clock until ``condition``, for at most ``timeout_s``."""
    end = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        rt.tick()


def test_a_high_five_over_dds_against_the_simulator_bridge_succeeds(tmp_path):
    from actions.dds.dds_action_bridge import DdsActionBridge
    from actions.dds.dds_action_client import DdsActionClient

    report_path = tmp_path / "bridge.json"
    bridge_process = subprocess.Popen(
        [sys.executable, "-m", "sim.cli", "bridge", "--domain", str(BRIDGE_DOMAIN),
         "--interface", "lo", "--duration", "600", "--report", str(report_path)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    robot = action_bridge = client = None
    try:
        robot = DdsRobot(domain_id=BRIDGE_DOMAIN, interface="lo")
        robot.wait_for_first_state(120.0)  # the bridge loads MuJoCo and compiles first
        loop = ControlLoop(robot, WholeBodyController(solver={"control_period_s": PERIOD_S}))
        action_bridge = DdsActionBridge(loop, domain_id=BRIDGE_DOMAIN, interface="lo")
        rt = RealtimeLoop(loop, rate_hz=500, bridge=action_bridge)
        client = DdsActionClient(HIGH_FIVE, "high_five", domain_id=BRIDGE_DOMAIN,
                                 interface="lo")
        rt.start()
        assert rt.rest.stand is None  # the bridge stands the robot until the first command
        run_until(rt, client.server_is_ready, "the action client to match", WAIT_S)
        future = client.send_goal_async(HighFiveGoal(target_height=0.3, hold_seconds=1))
        run_until(rt, lambda: future.done() and future.result().status.is_terminal,
                  "the high five to end", 60.0)
        wrapped = future.result().get_result_async().result(timeout=WAIT_S)
        assert wrapped.status == GoalStatus.SUCCEEDED, wrapped.result.message
        rt.request_stop("the test is over")
        run_until(rt, lambda: rt.done, "the robot to come to rest", 30.0)
        report = rt.report()
        assert report["stop"]["notes"] == ["sit ended SUCCEEDED", "damping (at rest)"]
        assert report["robot"]["bad_frames"] == 0 and report["robot"]["commands_refused"] == 0
        assert report["robot"]["commands_sent"] == report["ticks"]
        assert report["deadline_misses"] < 0.1 * report["ticks"]  # a busy 2-core machine
    finally:
        for closeable in (client, action_bridge, robot):
            if closeable is not None:
                closeable.close()
        bridge_process.send_signal(signal.SIGTERM)
        try:
            output, _ = bridge_process.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            bridge_process.kill()
            output, _ = bridge_process.communicate()
    assert bridge_process.returncode == 0, output
    stats = json.loads(report_path.read_text())["stats"]
    assert stats["commands_rejected"] == {} and stats["replies_unmatched"] == 0
    assert stats["latency_ms"]["count"] > 1000 and stats["latency_ms"]["median"] < 5.0


class PacedRobot(TestRobot):
    """A simulated GO2 whose states arrive every ``period_s`` on the fake clock, the first at
    ``first_s``: it tells the loop whether one is waiting, and records each one's age when
    read."""

    __test__ = False

    def __init__(self, plant: MujocoRobot, clock: FakeClock, *, period_s: float,
                 first_s: float) -> None:
        super().__init__(plant, clock)
        self.period_s = period_s
        self.next_s = clock.t + first_s
        self.ages_s: list[float] = []
        self.counters = DdsRobotCounters()  # ticks_skipped, as a DdsRobot counts them

    def wait_for_new_state(self, timeout_s: float) -> bool:
        if self.clock.t >= self.next_s:
            return True
        if self.next_s <= self.clock.t + timeout_s:
            self.clock.t = self.next_s
            return True
        self.clock.t += timeout_s
        return False

    def read_sensors(self) -> SensorRecord | None:
        if self.clock.t < self.next_s:
            return None
        while self.next_s + self.period_s <= self.clock.t:  # the newest only
            self.next_s += self.period_s
            self.counters.ticks_skipped += 1
        self.ages_s.append(self.clock.t - self.next_s)
        self.next_s += self.period_s
        return self.robot.read_sensors()


def paced_loop(*, period_s: float, first_s: float) -> tuple[RealtimeLoop, PacedRobot]:
    clock = FakeClock()
    sim = Go2Simulator(timestep_s=1e-3)
    plant = MujocoRobot(sim, control_period_s=PERIOD_S, sensor_seed=0)
    sim.reset("standing")
    plant.sensors.reset()
    robot = PacedRobot(plant, clock, period_s=period_s, first_s=first_s)
    robot.next_s -= period_s  # the loop is built from the state before
    loop = ControlLoop(robot, WholeBodyController(solver={"control_period_s": PERIOD_S}))
    return realtime(loop, clock), robot


@pytest.mark.parametrize("first_s", [0.0003, 0.0015])  # arriving 0.3 ms and 1.5 ms after
def test_the_ticks_find_the_states_arrival_and_follow_it(first_s):
    rt, robot = paced_loop(period_s=PERIOD_S, first_s=first_s)
    for _ in range(100):
        rt.tick()
    # The first tick may wait in vain (the state comes 1.5 ms after it); within
    # 1.5 ms / ALIGN_STEP_S = 75 ticks, each tick starts within a step of the arrival.
    assert rt.stats.no_fresh_state == rt.align_timeouts <= 1
    start = len(robot.ages_s)
    for _ in range(200):
        rt.tick()
    assert max(robot.ages_s[start:]) <= 2e-5 + 1e-9 and len(robot.ages_s) == start + 200
    assert rt.stats.no_fresh_state <= 1 and rt.align_timeouts <= 1
    longest_wait_s = min(first_s, rt.align_s)  # the first tick's (in vain past align_s)
    assert rt.stats.summary()["align"]["max_ms"] == pytest.approx(1e3 * longest_wait_s)


def test_a_late_state_is_answered_in_its_tick_and_barely_moves_the_deadlines():
    rt, robot = paced_loop(period_s=PERIOD_S, first_s=0.0003)
    for _ in range(100):
        rt.tick()
    assert rt.align_s == pytest.approx(0.5 * PERIOD_S)  # the default: half the period
    no_state, start = rt.stats.no_fresh_state, len(robot.ages_s)
    robot.next_s += 8e-4  # the next state comes 0.8 ms late (the robot's jitter)
    rt.tick()  # waits for it: answered on arrival, not skipped for the next one
    robot.next_s -= 8e-4  # the ones after it are on time again
    assert 0.8 <= rt.stats.summary()["align"]["max_ms"] <= 0.8 + 1e3 * ALIGN_STEP_S + 1e-6
    for _ in range(50):
        rt.tick()
    ages = robot.ages_s[start:]
    assert rt.stats.no_fresh_state == no_state and len(ages) == 51
    # The deadlines moved by ALIGN_FOLLOW_S (not 0.8 ms): the next states wait that long at
    # most, and after ALIGN_FOLLOW_S / ALIGN_STEP_S = 5 ticks, a step.
    assert max(ages) <= ALIGN_FOLLOW_S + 1e-9 and max(ages[7:]) <= ALIGN_STEP_S + 1e-9
    assert rt.stats.misses == 0


def test_the_states_skipped_while_running_exclude_the_start_ups():
    rt, robot = paced_loop(period_s=PERIOD_S, first_s=0.0003)
    robot.clock.advance(5 * PERIOD_S)  # the loop is being set up: 5 states come meanwhile
    for _ in range(100):
        rt.tick()
    # The first tick read the newest of them: 4 skipped, before the loop ran.
    assert robot.counters.ticks_skipped == 4 and rt.state_ticks_skipped == 0
    robot.clock.advance(2.5 * PERIOD_S)  # the loop is held up: two states come meanwhile
    for _ in range(100):
        rt.tick()
    assert robot.counters.ticks_skipped == 5 and rt.report()["state_ticks_skipped"] == 1


def test_the_alignment_pauses_for_a_robot_slower_than_the_loop():
    rt, _ = paced_loop(period_s=2 * PERIOD_S, first_s=0.001)  # 250 Hz states
    for _ in range(1200):
        rt.tick()
    assert rt.align_pauses == 2  # after 0.1 s, and 2 s later
    assert rt.stats.no_fresh_state >= 550  # every other tick: none to wait for
    assert rt.align_timeouts <= 2 * 0.1 * 500 / 2 + 2  # half the ticks of two windows
