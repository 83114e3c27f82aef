"""``go2-wbc bridge`` (:class:`sim.dds_bridge.DdsBridge`): the simulated GO2 on rt/lowstate and
rt/lowcmd over loopback DDS, in-process (stepped on a simulated clock, or run on a thread)
and as a ``go2-wbc bridge`` process."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from cyclonedds.core import (
    DDSStatus,
    InstanceState,
    Policy,
    Qos,
    ReadCondition,
    SampleState,
    ViewState,
    WaitSet,
)
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from sim.bridge_config import BridgeConfig
from sim.bridge_stats import BridgeStats
from sim.cli import main
from sim.command_slot import COMMAND, DAMPING, STAND, CommandSlot
from sim.dds_bridge import DdsBridge
from sim.sim_truth import SIM_TRUTH_DTYPE, SIM_TRUTH_TOPIC, SimTruth, SimTruthMessage
from tests.sweeps import quick_first
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES, Go2Description
from wbc.model.joint_map import JointMap
from wbc.robot_io.dds.c_layout import crc_ok, sdk_default_low_cmd, set_crc, zero_record
from wbc.robot_io.dds.domain_config import delete_entities, host_interfaces, join_domain
from wbc.robot_io.dds.go2_types import LOW_CMD_TOPIC, LOW_STATE_TOPIC
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage
from wbc.robot_io.motor_command import MotorCommand

ROOT = Path(__file__).resolve().parents[1]
DOMAIN_ID = 200 + os.getpid() % 30  # concurrent test runs stay apart
WAIT_S = 10.0  # the longest wait for a DDS sample or match (bounded, never a sleep)
PROCESS_START_S = 60.0  # a go2-wbc process's imports and start on a loaded machine
DT = 1e-3
STAND_SDK = Go2Description.default().pose("standing")[7:][JointMap.unitree_sdk().index]
CALVES_SDK = [UNITREE_SDK_JOINT_NAMES.index(f"{leg}_calf_joint") for leg in LEGS]
FR_CALF_Q = 7 + JOINT_NAMES.index("FR_calf_joint")  # in the truth's q (description order)
#: A crouch: every calf bent 0.3 rad more than standing.
CROUCH_SDK = STAND_SDK.copy()
CROUCH_SDK[CALVES_SDK] -= 0.3


# --- helpers --------------------------------------------------------------------------------


class Clock:
    """A simulated clock: the tests advance it one physics step per bridge step."""

    def __init__(self) -> None:
        self.now_s = 0.0

    def __call__(self) -> float:
        return self.now_s


class Peer:
    """A controller's side on the test domain: a LowCmd_ writer (unitree_sdk2's QoS), and
    readers of LowState_ and of the truth."""

    def __init__(self) -> None:
        self.dds = join_domain("lo", domain_id=DOMAIN_ID)
        p = self.dds.participant
        reliable = Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
                       Policy.History.KeepLast(1))
        keep = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(64))
        self.cmd = DataWriter(p, Topic(p, LOW_CMD_TOPIC, LowCmdMessage), qos=reliable)
        self.state = DataReader(p, Topic(p, LOW_STATE_TOPIC, LowStateMessage), qos=keep)
        self.truth = DataReader(p, Topic(p, SIM_TRUTH_TOPIC, SimTruthMessage), qos=keep)
        self.waits = {}
        for reader in (self.state, self.truth):
            waitset = WaitSet(p)
            waitset.attach(ReadCondition(reader, SampleState.Any | ViewState.Any
                                         | InstanceState.Any))
            self.waits[reader] = waitset

    def wait_for_bridge(self) -> None:
        """Wait until the bridge's writers and reader have matched ours (discovery)."""
        for entity, status, matched in (
                (self.state, DDSStatus.SubscriptionMatched,
                 lambda: self.state.get_subscription_matched_status().current_count),
                (self.truth, DDSStatus.SubscriptionMatched,
                 lambda: self.truth.get_subscription_matched_status().current_count),
                (self.cmd, DDSStatus.PublicationMatched,
                 lambda: self.cmd.get_publication_matched_status().current_count)):
            waitset = WaitSet(self.dds.participant)
            mask = entity.get_status_mask()
            entity.set_status_mask(status)  # the entity wakes the waitset when it matches
            waitset.attach(entity)
            deadline = time.monotonic() + WAIT_S
            try:
                while matched() < 1:
                    assert time.monotonic() < deadline, "the bridge was not discovered in time"
                    waitset.wait(duration(milliseconds=100))
            finally:
                waitset.detach(entity)
                entity.set_status_mask(mask)

    def take(self, reader: DataReader, timeout_s: float = 0.1) -> list[Any]:
        """The samples ``reader`` has, waiting up to ``timeout_s`` for one."""
        self.waits[reader].wait(duration(seconds=timeout_s))
        return [s for s in reader.take(N=256) if s.sample_info.valid_data]

    def sample_with_tick(self, reader: DataReader, tick: int) -> np.ndarray:
        """The record ``reader`` receives with ``tick`` (older ones skipped)."""
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline:
            for sample in self.take(reader):
                if int(sample.record["tick"]) == tick:
                    return sample.record
        raise AssertionError(f"no sample with tick {tick} within {WAIT_S} s")

    def close(self) -> None:
        delete_entities(self.cmd, self.state, self.truth)
        self.dds.close()


def low_cmd(q_sdk: np.ndarray, *, reply_tick: int = 0, kp: float = 60.0, kd: float = 5.0,
            fault: str | None = None) -> LowCmdMessage:
    """A LowCmd_ holding ``q_sdk`` with a joint PD; ``fault`` spoils one thing."""
    record = sdk_default_low_cmd()
    motors = record["motor_cmd"]
    motors["q"][:12] = q_sdk
    motors["dq"][:12] = 0.0
    motors["kp"][:12] = -1.0 if fault == "motor_cmd" else kp
    motors["kd"][:12] = kd
    motors["tau"][:12] = 0.0
    record["reserve"] = reply_tick
    if fault == "head":
        record["head"][0] = 0xFD
    if fault == "level_flag":
        record["level_flag"] = 0xEE  # the SDK's HIGHLEVEL
    set_crc(record)
    if fault == "crc":
        record["crc"] ^= 1
    return LowCmdMessage(record)


def step(bridge: DdsBridge, clock: Clock, n: int = 1) -> None:
    for _ in range(n):
        clock.now_s += DT
        bridge.step()


def drive_until(bridge: DdsBridge, clock: Clock, peer: Peer, message: Any, done: Any) -> None:
    """Write ``message`` and step, as a controller at 1 kHz would, until ``done()``."""
    deadline = time.monotonic() + WAIT_S
    while not done():
        assert time.monotonic() < deadline, "the bridge took no command in time"
        message.record["reserve"] = bridge.tick
        set_crc(message.record)
        peer.cmd.write(message)
        step(bridge, clock)


@pytest.fixture
def peer() -> Iterator[Peer]:
    peer = Peer()
    try:
        yield peer
    finally:
        peer.close()


@pytest.fixture
def stepped() -> Iterator[tuple[DdsBridge, Clock]]:
    """A started bridge on a simulated clock, exact sensors, 500 Hz."""
    clock = Clock()
    bridge = DdsBridge(BridgeConfig(domain_id=DOMAIN_ID, sensors="exact"), clock=clock)
    try:
        bridge.start()
        yield bridge, clock
    finally:
        bridge.close()


@pytest.fixture
def connected(stepped, peer) -> tuple[DdsBridge, Clock, Peer]:
    """The stepped bridge and the peer, discovered by each other."""
    peer.wait_for_bridge()
    return (*stepped, peer)


# --- without DDS ----------------------------------------------------------------------------


def test_truth_message_encodes_like_its_idl_type() -> None:
    rng = np.random.default_rng(3)
    record = zero_record(SIM_TRUTH_DTYPE)
    for name in ("t_s", "q", "v", "foot_position_m", "foot_force_n"):
        record[name] = rng.normal(size=record[name].shape)
    record["tick"] = 4_000_000_000
    idl = SimTruth(tick=4_000_000_000, t_s=float(record["t_s"]), q=record["q"].tolist(),
                   v=record["v"].tolist(), foot_position_m=record["foot_position_m"].tolist(),
                   foot_force_n=record["foot_force_n"].tolist())
    for xcdr2 in (False, True):
        assert SimTruthMessage(record).serialize(xcdr2) == idl.serialize(use_version_2=xcdr2)
    assert SimTruthMessage.deserialize(idl.serialize()).record.tobytes() == record.tobytes()


def test_command_slot_stands_then_commands_then_damps_on_timeout() -> None:
    slot = CommandSlot(STAND_SDK, timeout_s=0.1, delay_steps=2)
    command = MotorCommand.pure_torque(np.full(12, 1.0))
    modes = []
    for k in range(110):
        applied = slot.step(command if k in (0, 1) else None, now_s=k * DT)
        modes.append(slot.mode)
        if k < 2:
            assert applied is slot.stand  # still in the delay line
    assert modes[:2] == [STAND, STAND] and modes[2:4] == [COMMAND, COMMAND]
    assert slot.applied == 2 and slot.in_flight == 0
    # The last command was applied at step 3 (t = 3 ms): damping once 0.1 s have passed.
    assert modes.index(DAMPING) == 104 and slot.timeouts == 1
    assert slot.step(command, now_s=0.2) is slot.damping  # in the delay line
    assert slot.step(None, now_s=0.201) is slot.damping
    assert slot.step(None, now_s=0.202) is command and slot.transition == (DAMPING, COMMAND)


def test_stats_count_lost_repeated_and_unmatched_replies() -> None:
    stats = BridgeStats()
    for tick in range(1, 11):
        stats.published(tick, tick * 2e-3, tick * 2_000_000)
    stats.replied(1, 3e-3, 2_500_000, received_s=2.7e-3)  # written 0.5 ms after tick 1,
    #                                      arrived 0.7 ms after, taken 1 ms after
    stats.replied(2, 5e-3, None)
    stats.replied(5, 11e-3, None)          # ticks 3 and 4 got no reply
    stats.replied(5, 12e-3, None)          # the same tick again
    stats.replied(0, 12e-3, None)          # a controller that does not echo
    stats.replied(77, 12e-3, None)         # never published
    assert (stats.replies_lost, stats.replies_repeated, stats.replies_unmatched) == (2, 1, 2)
    np.testing.assert_allclose(stats.latency.values(), [1e-3, 1e-3, 1e-3, 2e-3])
    np.testing.assert_allclose(stats.reply.values(), [0.5e-3])
    # Arrival unknown: the step that took it.
    np.testing.assert_allclose(stats.received.values(), [0.7e-3, 1e-3, 1e-3, 2e-3])
    assert stats.as_dict()["latency_ms"]["max"] == pytest.approx(2.0)


# --- stepped on a simulated clock -----------------------------------------------------------


def test_a_valid_command_drives_a_joint(connected) -> None:
    bridge, clock, peer = connected
    step(bridge, clock, 500)  # the stand PD holds the pose
    hold = bridge.sim.state()[0][FR_CALF_Q]
    message = low_cmd(CROUCH_SDK)
    drive_until(bridge, clock, peer, message, lambda: bridge.stats.commands_applied > 0)
    assert bridge.mode == COMMAND
    for _ in range(300):  # 0.3 s more, commanded every step
        message.record["reserve"] = bridge.tick
        set_crc(message.record)
        peer.cmd.write(message)
        step(bridge, clock)
    step(bridge, clock, 2)  # one of them publishes the state after the last command
    truth = peer.sample_with_tick(peer.truth, bridge.tick)
    assert hold - truth["q"][FR_CALF_Q] > 0.25  # most of the 0.3 rad step
    stats = bridge.stats
    assert stats.commands_rejected == {} and stats.commands_applied == stats.commands_received
    assert stats.latency.summary()["count"] == stats.commands_applied - stats.replies_unmatched


def test_every_command_that_arrives_is_counted_once(connected) -> None:
    bridge, clock, peer = connected
    step(bridge, clock)  # publishes tick 1
    stats = bridge.stats
    # Two within one physics step: the newest is applied, the older superseded (a robot's
    # KeepLast 1 reader would have overwritten it), both answer tick 1.
    peer.cmd.write(low_cmd(STAND_SDK, reply_tick=1))
    peer.cmd.write(low_cmd(CROUCH_SDK, reply_tick=1))
    step(bridge, clock)
    assert (stats.commands_received, stats.commands_superseded, stats.commands_applied) == (
        2, 1, 1)
    np.testing.assert_allclose(bridge.slot.command.q_des, CROUCH_SDK, atol=1e-6)
    # A valid one overtaken by a bad one: nothing new is applied, as on the robot.
    peer.cmd.write(low_cmd(STAND_SDK, reply_tick=1))
    peer.cmd.write(low_cmd(STAND_SDK, reply_tick=1, fault="crc"))
    step(bridge, clock)
    assert (stats.commands_received, stats.commands_superseded, stats.commands_applied) == (
        4, 2, 1)
    assert stats.commands_rejected == {"crc": 1}
    np.testing.assert_allclose(bridge.slot.command.q_des, CROUCH_SDK, atol=1e-6)
    assert (stats.replies_lost, stats.replies_repeated) == (0, 2)
    # Still pending when the bridge closes: counted, never applied.
    for _ in range(3):
        peer.cmd.write(low_cmd(STAND_SDK, reply_tick=1))
    bridge.close()
    assert (stats.commands_received, stats.commands_after_stop) == (4, 3)
    assert stats.command_history_full == 0
    assert stats.as_dict()["commands_after_stop"] == 3


@pytest.mark.parametrize("fault", ["crc", "head", "level_flag", "motor_cmd"])
def test_a_bad_frame_is_dropped_counted_and_moves_nothing(connected, fault) -> None:
    bridge, clock, peer = connected
    step(bridge, clock, 500)  # the stand PD has (almost) settled
    hold = bridge.sim.state()[0][FR_CALF_Q]
    message = low_cmd(CROUCH_SDK, fault=fault)
    deadline = time.monotonic() + WAIT_S
    while bridge.stats.commands_received < 3:
        assert time.monotonic() < deadline, "the bridge received no command in time"
        peer.cmd.write(message)
        step(bridge, clock)
    step(bridge, clock, 200)
    stats = bridge.stats
    assert stats.commands_rejected == {fault: stats.commands_received}
    assert stats.commands_applied == 0 and bridge.mode == STAND
    assert stats.last_rejection[fault].startswith(f"LowCmd_.{fault}")
    assert abs(bridge.sim.state()[0][FR_CALF_Q] - hold) < 0.01


def test_command_timeout_damps_the_motors_and_commands_resume(connected) -> None:
    bridge, clock, peer = connected
    message = low_cmd(STAND_SDK, kp=100.0, kd=5.0)
    drive_until(bridge, clock, peer, message, lambda: bridge.stats.commands_applied >= 20)
    # The controller stops. The last command may still be on its way: the timeout counts
    # from the step that applies the last one.
    last_s, applied = clock.now_s, bridge.stats.commands_applied
    while bridge.mode == COMMAND:
        step(bridge, clock)
        if bridge.stats.commands_applied != applied:
            last_s, applied = clock.now_s, bridge.stats.commands_applied
        assert clock.now_s - last_s < 0.2
    assert bridge.mode == DAMPING and bridge.stats.timeouts == 1
    assert clock.now_s - last_s == pytest.approx(0.101, abs=1.5e-3)
    step(bridge, clock, 4500)  # damping: the robot sits down and stops (in 2 to 4 s)
    q, v = bridge.sim.state()
    assert q[2] < 0.12 and np.abs(v).max() < 0.05
    assert bridge.mode == DAMPING and bridge.stats.timeouts == 1
    drive_until(bridge, clock, peer, message,
                lambda: bridge.stats.commands_applied > applied)
    assert bridge.mode == COMMAND  # at once, from the step that took it


def test_truth_is_the_exact_state_and_lowstate_is_the_sensors(peer) -> None:
    clock = Clock()
    with DdsBridge(BridgeConfig(domain_id=DOMAIN_ID, rate_hz=1000), clock=clock) as bridge:
        bridge.start()
        peer.wait_for_bridge()
        step(bridge, clock, 300)
        q, v = bridge.sim.state()
        feet = bridge.sim.foot_position_array().copy()
        forces = bridge.sim.foot_normal_forces().copy()
        step(bridge, clock)  # publishes this state, then steps the physics
        tick = bridge.tick
        truth = peer.sample_with_tick(peer.truth, tick)
        state = peer.sample_with_tick(peer.state, tick)
    assert truth["t_s"] == pytest.approx(0.3)
    assert np.array_equal(truth["q"], q) and np.array_equal(truth["v"], v)
    assert np.array_equal(truth["foot_position_m"], feet)
    assert np.array_equal(truth["foot_force_n"], forces) and forces.sum() > 100.0
    # LowState_: the sensors (noisy; float32), in the SDK's order, with the SDK's header.
    assert crc_ok(state) and state["head"].tolist() == [0xFE, 0xEF]
    assert state["level_flag"] == 0xFF and state["motor_state"]["mode"][:12].tolist() == [1] * 12
    joints_sdk = q[7:][JointMap.unitree_sdk().index]
    measured = state["motor_state"]["q"][:12]
    assert not np.array_equal(measured, joints_sdk.astype(np.float32))
    np.testing.assert_allclose(measured, joints_sdk, atol=2e-3)
    w, x, y, z = state["imu_state"]["quaternion"]
    assert abs(abs(np.dot([x, y, z, w], q[3:7])) - 1.0) < 1e-4  # wxyz vs Pinocchio's xyzw


# --- running on the clock -------------------------------------------------------------------


def test_run_on_a_thread_publishes_and_stops(peer) -> None:
    bridge = DdsBridge(BridgeConfig(domain_id=DOMAIN_ID))
    thread = threading.Thread(target=bridge.run, name="bridge")
    try:
        thread.start()
        deadline = time.monotonic() + WAIT_S
        ticks: list[int] = []
        while len(ticks) < 20:
            assert time.monotonic() < deadline, "no LowState_ from the bridge in time"
            ticks += [int(s.record["tick"]) for s in peer.take(peer.state)]
        assert ticks == sorted(set(ticks))
    finally:
        bridge.stop()
        thread.join(timeout=WAIT_S)
        bridge.close()
    assert not thread.is_alive() and not bridge.is_started
    assert bridge.stats.states_published >= 20


def test_a_command_is_stamped_when_it_arrives_between_physics_steps(peer) -> None:
    """Between steps the bridge waits on its command reader: the "received" latency is the
    arrival, the "taken" one the next step (here 0.1 s later)."""
    with DdsBridge(BridgeConfig(domain_id=DOMAIN_ID, sensors="exact")) as bridge:
        bridge.start()
        peer.wait_for_bridge()
        bridge.step()  # publishes tick 1
        peer.cmd.write(low_cmd(STAND_SDK, reply_tick=bridge.tick))
        bridge._intake.wait_until(time.monotonic() + 0.1, time.monotonic)
        bridge.step()
        stats = bridge.stats
        assert (stats.commands_received, stats.commands_applied) == (1, 1)
        (received_s,), (taken_s,) = stats.received.values(), stats.latency.values()
    assert taken_s >= 0.1 and 0.0 < received_s < taken_s - 0.05


def test_viewer_without_a_display_runs_headless(monkeypatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    events: list[str] = []
    with DdsBridge(BridgeConfig(domain_id=DOMAIN_ID, viewer=True),
                   on_event=lambda t_s, text: events.append(text)) as bridge:
        bridge.start()
        bridge.step()
    assert events == [("--viewer: no display ($DISPLAY and $WAYLAND_DISPLAY are unset); "
                       "running headless")]


# --- go2-wbc bridge -------------------------------------------------------------------------


def bridge_process(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "sim.cli", "bridge", "--domain",
                             str(DOMAIN_ID), *args], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


# The GO2's 500 Hz in the quick stage, 1000 Hz in the slow one (``make test-slow``).
@pytest.mark.parametrize("rate_hz", quick_first([500, 1000], lambda rate_hz: rate_hz == 500))
def test_publishes_at_its_rate_and_stops_on_sigterm(peer, rate_hz) -> None:
    process = bridge_process("--rate", str(rate_hz))
    try:
        received: list[tuple[float, int]] = []
        deadline = time.monotonic() + PROCESS_START_S
        while not received or received[-1][0] - received[0][0] < 0.5:
            assert time.monotonic() < deadline and process.poll() is None, "no LowState_"
            for sample in peer.take(peer.state):
                assert crc_ok(sample.record)
                received.append((time.monotonic(), int(sample.record["tick"])))
        ticks = [tick for _, tick in received]
        assert ticks == sorted(set(ticks))  # increasing, none twice
        (t0, first), (t1, last) = received[0], received[-1]
        assert (last - first) / (t1 - t0) == pytest.approx(rate_hz, rel=0.1)
        process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=WAIT_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 0, err
    assert "stopped by SIGTERM" in out and "\nstates published " in out


def test_duration_exits_0_with_a_summary_report_and_log(tmp_path) -> None:
    report, log = tmp_path / "bridge.json", tmp_path / "truth.npz"
    process = bridge_process("--duration", "1", "--report", str(report), "--log", str(log))
    try:
        out, err = process.communicate(timeout=PROCESS_START_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == 0, err
    stats = json.loads(report.read_text())["stats"]
    states = stats["states_published"]
    # 500 in 1 s at 500 Hz, fewer if the pacing had to resynchronise (steps are not made up).
    assert 500 - 10 * stats["overruns"] <= states <= 500 and stats["commands_received"] == 0
    assert "stopped by --duration after" in out and f"\nstates published {states} at" in out
    arrays = np.load(log)
    assert arrays["q"].shape == (states, 19) and arrays["v"].shape == (states, 18)
    assert arrays["foot_position_m"].shape == (states, 4, 3)
    np.testing.assert_array_equal(arrays["tick"], np.arange(1, states + 1))
    np.testing.assert_allclose(arrays["t_s"], np.arange(states) * 2e-3, atol=1e-9)
    assert arrays["joint_names"].tolist() == list(JOINT_NAMES)


@pytest.mark.parametrize(("args", "message"), [
    (["--interface", "nosuch0"], ("--interface: expected one of this host's network "
                                  f"interfaces {host_interfaces()}, received 'nosuch0'")),
    (["--domain", "233"], ("--domain: expected a DDS domain id in [0, 232] (a GO2: 0; the "
                           "simulator bridge: 1), received 233")),
    (["--rate", "300"], ("--rate: expected 1000 Hz divided by a whole number (the physics "
                         "runs at 1000 Hz: 1000, 500, 250, 200, 125, 100, ...), received 300")),
    (["--rate", "2000"], "--rate: expected a rate in [1, 1000] Hz, received 2000"),
    (["--command-delay", "0.0015"], ("--command-delay: expected a whole number of 0.001 s "
                                     "physics steps (e.g. 0.002, 0.009), received 0.0015")),
])
def test_bad_options_name_themselves(capsys, args, message) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["bridge", *args])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert err == f"go2-wbc bridge: error: {message} (see 'go2-wbc bridge --help')\n"


def test_config_checks_its_fields() -> None:
    with pytest.raises(ConfigurationError, match=r"^rate_hz: expected 1000 Hz divided"):
        BridgeConfig(rate_hz=300)
    with pytest.raises(ConfigurationError, match=r"^interface: expected one of"):
        BridgeConfig(interface="nosuch0")
    with pytest.raises(ConfigurationError, match=r"^command_timeout_s: expected a value in "
                                                 r"\(0, 10\], received 0$"):
        BridgeConfig(command_timeout_s=0.0)
    with pytest.raises(ConfigurationError, match=r"^pose: expected one of standing, lying, "
                                                 r"received 'sitting'$"):
        BridgeConfig(pose="sitting")
