"""The kinds of ``rt/lowstate`` stream (:mod:`wbc.robot_io.dds.stream_kind`) and a stream's
new samples, repeats, rate and staleness limit (:mod:`wbc.robot_io.dds.low_state_stream`), on
synthetic ``LowState_`` records framed as a GO2, Unitree's C++ simulator and Unitree's Python
simulator frame them (no DDS but in one test: a DdsRobot on such a stream); and the one
staleness limit the loop shares with the estimator."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest
from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration

from actions.robot.control_loop import ControlLoop
from actions.robot.dds_robot import DdsRobot
from actions.robot.realtime_loop import RealtimeLoop
from actions.robot.state_fallback import stream_note
from sim.cli.parser import build_parser
from sim.cli.run_dds import run_dds
from sim.mujoco_robot import MujocoRobot
from sim.simulator import Go2Simulator
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.estimation.estimators import make_estimator
from wbc.robot_io.dds.c_layout import HEAD, LOW_STATE_DTYPE, set_crc, zero_record
from wbc.robot_io.dds.domain_config import delete_entities, join_domain
from wbc.robot_io.dds.go2_types import LOW_STATE_TOPIC
from wbc.robot_io.dds.low_state_stream import (
    CLASSIFY_STATES,
    RATE_SAMPLES,
    LowStateStream,
    default_stale_after_s,
)
from wbc.robot_io.dds.stream_kind import (
    GO2,
    UNITREE_CPP,
    UNITREE_PYTHON,
    StreamKind,
    framing_of,
)
from wbc.robot_io.dds.wire_message import LowStateMessage


def state(n: int, framing: str = GO2, *, tick: int | None = None,
          foot_force: int = 0) -> np.ndarray:
    """The ``n``-th state of a robot framed as ``framing`` (its joints move with ``n``)."""
    record = zero_record(LOW_STATE_DTYPE)
    record["imu_state"]["quaternion"] = (1.0, 0.0, 0.0, 0.0)
    record["imu_state"]["accelerometer"] = (0.0, 0.0, 9.81)
    record["motor_state"]["q"][:12] = np.linspace(-1.0, 1.0, 12) + 1e-3 * n
    record["foot_force"] = foot_force
    if framing == UNITREE_PYTHON:  # head 00 00, crc 0, tick 0
        record["tick"] = 0 if tick is None else tick
        return record
    record["tick"] = n if tick is None else tick
    if framing == GO2:
        record["head"] = HEAD
    set_crc(record)
    return record


def fed(stream: LowStateStream, records: list[np.ndarray], *, period_s: float = 0.005,
        start_s: float = 0.0) -> list[bool]:
    """What ``stream.accept`` said of each record, arriving one ``period_s`` apart."""
    return [stream.accept(r, start_s + k * period_s) for k, r in enumerate(records)]


# -- framing --------------------------------------------------------------------------------


@pytest.mark.parametrize("framing", [GO2, UNITREE_CPP, UNITREE_PYTHON])
def test_each_framing_is_recognised_from_head_and_crc(framing):
    assert framing_of(state(3, framing)) == (framing, "")


def test_frames_that_fit_no_framing_are_refused_with_the_field_and_what_is_valid():
    go2 = state(3)
    go2["crc"] ^= 1
    assert framing_of(go2) == (None, (f"LowState_.crc: 0x{int(go2['crc']):08X} does not match "
                                     "the content (a frame with head FE EF carries a CRC)"))
    cpp = state(3, UNITREE_CPP)
    cpp["crc"] ^= 1
    assert framing_of(cpp)[1] == (
        f"LowState_.crc: 0x{int(cpp['crc']):08X} does not match the content (valid: the "
        "content's CRC, or 0 for a stream without one)")
    odd = state(3)
    odd["head"] = (0xFE, 0x00)
    assert framing_of(odd) == (None, ("LowState_.head: expected FE EF (a GO2) or 00 00 "
                                     "(Unitree's simulators), received FE 00"))


def test_a_kind_says_what_it_checks():
    assert StreamKind(GO2, ticks=True).describe() == (
        "go2 (a GO2 or go2-wbc bridge): head FE EF, CRC checked; a new sample has a new tick")
    assert StreamKind(UNITREE_PYTHON, ticks=False).describe() == (
        "unitree-python (Unitree's Python simulator (unitree_mujoco simulate_python)): head "
        "00 00, no CRC (sent as 0: not checked); tick not counting: a new sample has new "
        "content (the same bytes again are a repeat)")
    assert StreamKind(UNITREE_CPP, ticks=True).crc_checked


# -- the kind, from the first states ----------------------------------------------------------


@pytest.mark.parametrize("framing, ticks", [(GO2, True), (UNITREE_CPP, True),
                                            (UNITREE_PYTHON, False)])
def test_the_kind_is_decided_from_the_first_states_and_every_new_one_is_used(framing, ticks):
    stream = LowStateStream()
    verdicts = fed(stream, [state(n, framing) for n in range(1, CLASSIFY_STATES)])
    assert verdicts == [True] * (CLASSIFY_STATES - 1) and stream.kind is None
    assert fed(stream, [state(CLASSIFY_STATES, framing)]) == [True]
    assert stream.kind == StreamKind(framing, ticks=ticks)
    assert fed(stream, [state(n, framing) for n in range(10, 30)]) == [True] * 20
    assert stream.counters.new_samples == CLASSIFY_STATES + 20
    assert stream.counters.repeats == stream.counters.dropped == 0


def test_a_go2_framed_stream_whose_tick_stays_0_is_used_by_its_content():
    """The issue's case: head and CRC stamped, tick left at 0 (1 state used of ~11,000)."""
    stream = LowStateStream()
    records = [state(n, GO2, tick=0) for n in range(1, 41)]
    assert fed(stream, records) == [True] * 40
    assert stream.kind == StreamKind(GO2, ticks=False)
    assert fed(stream, [records[-1]]) == [False]  # the same bytes again: a repeat
    assert stream.counters.repeats == 1


def test_python_simulator_repeats_are_told_by_their_bytes_and_named_when_frozen():
    stream = LowStateStream()
    fed(stream, [state(n, UNITREE_PYTHON) for n in range(1, 11)])
    frozen = state(10, UNITREE_PYTHON)
    assert fed(stream, [frozen] * 7, start_s=1.0, period_s=0.005) == [False] * 7
    assert stream.counters.repeats == 7
    assert stream.stale_reason(1.04) == (
        "rt/lowstate keeps arriving (7 state(s) in the last 995 ms) but never changes: the "
        "same bytes each time (tick 0): a frozen sensor stream")
    assert fed(stream, [state(11, UNITREE_PYTHON)], start_s=1.05) == [True]
    assert stream.stale_reason(1.06) == ""  # nothing arrived since the new one


def test_a_counting_tick_that_freezes_makes_repeats_even_when_the_content_changes():
    stream = LowStateStream()
    fed(stream, [state(n) for n in range(1, 11)])
    assert stream.kind == StreamKind(GO2, ticks=True)
    stuck = [state(n, tick=10) for n in range(11, 16)]
    assert fed(stream, stuck, start_s=1.0) == [False] * 5
    assert (stream.counters.repeats, stream.counters.tick_frozen) == (5, 5)
    assert stream.stale_reason(1.02).endswith(
        "but never changes: its tick stays at 10 while its content changes (a stream whose "
        "tick counted froze)")


def test_skipped_ticks_and_restarts_are_counted_on_a_go2_stream_only():
    stream = LowStateStream()
    fed(stream, [state(n) for n in (1, 2, 3, 4, 5, 9, 3)])
    assert (stream.counters.ticks_skipped, stream.counters.tick_restarts) == (3, 1)
    cpp = LowStateStream()  # its tick is the simulated time in ms: steps of 2 at 500 Hz
    fed(cpp, [state(n, UNITREE_CPP, tick=2 * n) for n in range(1, 8)])
    assert cpp.counters.ticks_skipped == 0


def test_a_frame_of_another_kind_is_dropped_after_the_decision_and_restarts_it_before():
    stream = LowStateStream()
    fed(stream, [state(1, UNITREE_PYTHON), state(2, UNITREE_PYTHON), state(3)])
    assert stream.counters.kind_switches == 1 and stream.kind is None
    fed(stream, [state(n) for n in range(4, 8)])
    assert stream.kind == StreamKind(GO2, ticks=True)
    assert fed(stream, [state(8, UNITREE_CPP)]) == [False]
    assert stream.counters.dropped == 1
    assert stream.last_fault == ("LowState_ framing: the stream is go2 (head FE EF), this frame "
                                 "is unitree-cpp: a second publisher, or a stream that changed "
                                 "kind")
    bad = state(9)
    bad["crc"] ^= 1
    assert fed(stream, [bad], start_s=2.0) == [False]
    assert stream.last_fault.startswith("LowState_.crc: ")
    assert stream.stale_reason(2.01).startswith("2 rt/lowstate frame(s) in the last")
    assert fed(stream, [state(10)]) == [True]


def test_decide_settles_on_fewer_states_and_says_so_at_start():
    stream = LowStateStream()
    assert stream.decide() is None
    assert stream.describe() == "rt/lowstate: no frame of a known kind yet"
    fed(stream, [state(1, UNITREE_CPP, tick=5), state(2, UNITREE_CPP, tick=10)])
    assert stream.decide() == StreamKind(UNITREE_CPP, ticks=True)
    assert stream.describe() == (
        "rt/lowstate: unitree-cpp (Unitree's C++ simulator (unitree_mujoco simulate)): head "
        "00 00, CRC checked; a new sample has a new tick; 200 Hz measured over 2 states "
        "(longest gap 5.0 ms); foot_force absent (0 in every state so far): the feet's contact "
        "comes from the schedule")


def test_one_state_is_taken_to_count_its_tick_unless_it_is_0():
    one = LowStateStream()
    fed(one, [state(7)])
    assert one.decide() == StreamKind(GO2, ticks=True)
    zero = LowStateStream()
    fed(zero, [state(7, UNITREE_PYTHON)])
    assert zero.decide() == StreamKind(UNITREE_PYTHON, ticks=False)


def test_foot_force_is_absent_until_a_state_carries_one():
    stream = LowStateStream()
    assert not stream.foot_force_absent  # nothing seen yet
    fed(stream, [state(n) for n in range(1, 4)])
    assert stream.foot_force_absent
    fed(stream, [state(4, foot_force=25)])
    assert not stream.foot_force_absent


def test_the_classification_size_is_checked():
    with pytest.raises(ConfigurationError, match=r"^classify_states: expected a whole number "
                                                 r">= 1, received 0$"):
        LowStateStream(classify_states=0)


# -- rate and staleness -----------------------------------------------------------------------


@pytest.mark.parametrize("rate_hz, expected_s", [(1000.0, 0.02), (500.0, 0.04),
                                                 (200.0, 0.1), (50.0, 0.25)])
def test_the_staleness_limit_is_twenty_periods_within_its_bounds(rate_hz, expected_s):
    assert default_stale_after_s(1.0 / rate_hz) == pytest.approx(expected_s)
    assert default_stale_after_s(1.0 / rate_hz, 0.0) == default_stale_after_s(1.0 / rate_hz)


def test_a_python_simulator_stream_with_gaps_gets_a_limit_above_its_gaps():
    """200 Hz with 10 to 50 ms gaps (Unitree's Python simulator on a loaded machine)."""
    rng = np.random.default_rng(0)
    arrivals = np.cumsum(np.where(rng.random(RATE_SAMPLES) < 0.1,
                                  rng.uniform(0.01, 0.05, RATE_SAMPLES), 0.005))
    stream = LowStateStream()
    for n, t in enumerate(arrivals):
        assert stream.accept(state(n, UNITREE_PYTHON), float(t))
    assert stream.period_s == pytest.approx(0.005)
    assert 0.01 < stream.longest_gap_s <= 0.05
    assert stream.stale_after_s() == pytest.approx(max(0.1, 2.0 * stream.longest_gap_s))
    assert stream.stale_after_s() > 0.05  # the longest gap measured on that simulator
    assert LowStateStream().stale_after_s() == 0.25  # unknown rate: the ceiling


# -- a DdsRobot on such a stream (in-process DDS) ---------------------------------------------


def test_a_dds_robot_uses_a_python_simulator_stream_and_names_it_when_frozen():
    """Head 00 00, crc 0, tick 0: every new state used, repeats not; a stream that keeps
    arriving unchanged is named in the note the fallback's reason carries."""
    domain = 190 + os.getpid() % 10
    dds = join_domain("lo", domain_id=domain)
    writer = DataWriter(dds.participant, Topic(dds.participant, LOW_STATE_TOPIC,
                                               LowStateMessage),
                        qos=Qos(Policy.Reliability.Reliable(duration(milliseconds=100)),
                                Policy.History.KeepLast(1)))
    robot = DdsRobot(domain_id=domain, interface="lo", dry_run=True)
    try:
        deadline = time.monotonic() + 10.0
        while not writer.get_publication_matched_status().current_count:
            assert time.monotonic() < deadline, "the robot's reader did not match"
            time.sleep(0.01)
        sent = [state(n, UNITREE_PYTHON) for n in range(1, 8)]
        for record in sent:
            writer.write(LowStateMessage(record))
            time.sleep(0.005)
        first = robot.wait_for_first_state(5.0)
        assert robot.stream.kind == StreamKind(UNITREE_PYTHON, ticks=False)
        assert first.tick == robot.stream.counters.new_samples  # a count: the estimator's
        assert robot.read_sensors() is not None and robot.read_sensors() is None
        for _ in range(5):  # the same bytes again
            writer.write(LowStateMessage(sent[-1]))
            time.sleep(0.005)
            assert robot.read_sensors() is None
        assert robot.counters.repeated_states == 5 and robot.counters.bad_frames == 0
        assert stream_note(robot).startswith(
            "; rt/lowstate keeps arriving (5 state(s) in the last ")
        assert stream_note(robot).endswith("but never changes: the same bytes each time "
                                           "(tick 0): a frozen sensor stream")
        writer.write(LowStateMessage(state(9, UNITREE_PYTHON)))
        time.sleep(0.02)
        assert robot.read_sensors() is not None and stream_note(robot) == ""
    finally:
        robot.close()
        delete_entities(writer)
        dds.close()


# -- one staleness setting --------------------------------------------------------------------


def test_the_loop_gives_the_estimator_its_staleness_limit():
    """One limit: a RealtimeLoop's ``stale_after_s`` becomes the estimator's
    ``trust_timeout_s`` (the estimator's 10 ms is not a second, tighter limit)."""
    sim = Go2Simulator(timestep_s=1e-3)
    plant = MujocoRobot(sim, control_period_s=0.002, sensor_seed=0)
    sim.reset("standing")
    plant.sensors.reset()
    loop = ControlLoop(plant, WholeBodyController(solver={"control_period_s": 0.002}),
                       estimator=make_estimator(control_period_s=0.002))
    assert loop.estimator.config.trust_timeout_s == 0.01
    rt = RealtimeLoop(loop, rate_hz=500, stale_after_s=0.1)
    assert rt.stale_after_s == loop.estimator.config.trust_timeout_s == 0.1


def test_run_dds_refuses_a_second_staleness_limit(capsys):
    with pytest.raises(SystemExit) as caught:  # refused where --set is read
        run_dds(build_parser().parse_args(["run", "--dds", "--set",
                                           "estimator.trust_timeout_s=0.5"]))
    assert caught.value.code == 2
    assert ("--set estimator.trust_timeout_s: set by --stale-after (one limit for the "
            "watchdog and the estimator)") in capsys.readouterr().err
