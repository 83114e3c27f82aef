"""Closed-loop scenarios across processes: the simulated GO2 (``go2-wbc bridge``), its
controller (``go2-wbc run --dds``) and goal clients (``go2-wbc high-five --dds``), each a
process on a private DDS domain on loopback, on the wall clock (:mod:`benchmarks.dds_processes`).

Each process is started and stopped by the test (Ctrl-C, ``kill -9``, SIGSTOP/SIGCONT as the
scenario says); whatever is left when a test fails is killed with its process group. The
scenarios after the first share one bridge (and, while it lives, one controller) to keep the
file fast, and run in the order b, c, e, d (d stops its controller with Ctrl-C, for its tick
log); each starts what it needs if it runs alone.

Scenarios a, b, d and e (15 to 30 s of wall clock each) are in the slow stage (``make
test-slow``); c, a goal across the three processes whose client is killed, is the quick
stage's.

Bounds are for a shared 2-core CI machine, looser than the benchmark's targets where timing
depends on the machine's load (``python -m benchmarks.realtime_loop`` measures those, against
the 0.1 % miss target); each test prints its figures (``pytest -s``). The share of deadline
misses is the machine's more than the controller's: one tree, one 2-core VM, thirteen runs of
test a one after the other gave 0.23 to 0.61 % nine times and 1.95, 2.06, 2.91 and 5.03 %
four times, those four with a tick's mean CPU time 8 to 23 % above the others' (the host's
load: the VM's steal time rose during one of them); CI gave 2.20 %. So the CI bounds are on what
a slower controller moves and a noisy host does not: the median CPU time of a tick (means
0.62 to 0.76 ms in those runs; the bound is half the period), and misses in at most 10 % of
the ticks (a loop that cannot keep up, as in test_dds_controller). The wire's latencies are
bounded stage over stage for the same reason: in CI, with a tick's median CPU time of 0.69 ms,
the state-to-command-received median was 1.03 ms (0.76 to 0.82 ms in quiet runs, against the
benchmark's 1 ms target), of which the command's delivery was 0.16 ms.

The bridge's and the controller's loops run real-time where the machine permits it (their
default), so that other processes cannot starve them; under ordinary scheduling, with other
CPU-bound processes on both cores (another test suite), the bridge was seen starved for 11 to
31 ms, the controller's watchdog damped the robot and the goal ended ABORTED (test a's failure
message then gives the longest gap without a state and the load average).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from actions.robot.state_fallback import FallbackSettings
from benchmarks.dds_outputs import (
    BridgeFigures,
    ControllerFigures,
    TruthMonitor,
    base_height_m,
    bridge_events,
    client_outcome,
    loop_scheduling,
    standing,
)
from benchmarks.dds_processes import DdsProcesses, ManagedProcess, private_domain_id
from benchmarks.realtime_loop import high_five_misses
from sim.cli.exit_codes import EXIT_INTERRUPTED, EXIT_NOT_SUCCEEDED, EXIT_SUCCEEDED
from sim.dds_evaluation import goal_runs

RATE_HZ = 500
#: Longest wall time [s] of a high five of 0.4 m held 2 s from the client's start (about 9 s).
GOAL_TIMEOUT_S = 30.0
#: How long [s] the truth must show the robot standing to count it as standing.
STANDING_HOLD_S = 0.5
#: How far into the raise [s] the client is interrupted or killed, or the bridge stalled
#: (the raise lasts 1.5 s).
INTO_RAISE_S = 0.4
#: How long [s] the bridge is frozen (SIGSTOP, SIGCONT).
STALL_S = 0.3

# CI bounds (module doc); the targets in comments.
MISS_PERCENT_MAX = 10.0       # target 0.1 % (the benchmark, on a quiet machine): module doc
CPU_MEDIAN_MAX_SHARE = 0.5    # of the period: a tick's median CPU time (module doc)
# The wire's latencies (medians, state written by the bridge -> ...), each beyond the stage
# before it, so that a slow host, which slows the controller's tick, is not counted twice
# (module doc; the absolute targets, 1 ms received, are the benchmark's):
WRITTEN_OVER_CPU_MAX_MS = 0.5   # ... command written, beyond a tick's median CPU time
RECEIVED_OVER_WRITTEN_MAX_MS = 0.5  # ... command received at the bridge, beyond written
TAKEN_OVER_RECEIVED_MAX_MS = 1.5    # ... taken by a physics step, beyond received: the wait
#                                   for the next 1 ms step (about 0.1 ms quiet), and a late one
RAISED_RMS_MAX_MM, HOLDING_RMS_MAX_MM = 5.0, 3.0
VELOCITY_RMS_MAX_MM_S, HEIGHT_MAX_MM, ROLL_PITCH_MAX_DEG = 20.0, 3.0, 0.3
TILT_MAX_DEG = 3.0
#: A silent robot gets the damped fallback command after the controller's staleness limit
#: (its report's ``stale_after_s``: 40 ms at 500 Hz, from the rate measured at start) plus at most
#: this [s]: a control period, and several more of scheduling on a busy CI machine (quiet,
#: 0.6 to 3.4 ms were measured).
DAMP_SLACK_S = 10.0 / RATE_HZ


def _seconds_since(start_s: float) -> float:
    return time.monotonic() - start_s


def _mid_raise(client: ManagedProcess) -> float:
    """Wait until ``client``'s goal is :data:`INTO_RAISE_S` into its raise; return when the
    raise was seen to start [s, monotonic]."""
    client.wait_for_line(r"^Feedback .*phase: raising", timeout_s=15.0)
    seen_s = time.monotonic()
    time.sleep(INTO_RAISE_S)  # the scenario's timing, not a synchronisation
    return seen_s


# -- a. three processes, one high five -------------------------------------------------------


@pytest.mark.slow
def test_a_high_five_across_three_processes_meets_the_quality_and_timing_bounds(
        tmp_path: Path) -> None:
    """Bridge, controller and client on the wall clock at 500 Hz: the high five SUCCEEDS; the
    logs joined on LowState_ tick give the quality figures; the reports the wire's."""
    start = time.monotonic()
    with DdsProcesses(tmp_path, domain_id=private_domain_id()) as run:
        bridge = run.bridge(rate_hz=RATE_HZ)
        controller = run.controller(rate_hz=RATE_HZ)
        client = run.high_five(height_m=0.4, hold_s=2.0)
        code = client.wait(GOAL_TIMEOUT_S)
        # Stopped whatever the goal's end: their reports explain a failure.
        assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
        assert bridge.stop() == 0, bridge.tail()
    assert code == EXIT_SUCCEEDED, (f"{client.tail()}\n{_longest_state_gap(controller.log_path)}"
                                    f"; load average {os.getloadavg()}")
    outcome = client_outcome(client.output())
    assert outcome.status == "SUCCEEDED"
    assert outcome.phases[-1] == "complete"
    wire = BridgeFigures.read(bridge.report_path)
    loop = ControllerFigures.read(controller.report_path)
    runs = goal_runs(controller.log_path, bridge.log_path)
    five = [r for r in runs if r.action == "high_five"]
    assert len(five) == 1, runs
    five_run = five[0]
    goal_rows = high_five_misses(controller.log_path)
    print(f"\na. {_seconds_since(start):.1f} s wall, load average {os.getloadavg()[0]:.2f}; "
          f"controller: {loop.ticks} ticks, "
          f"{loop.deadline_misses} deadline misses ({loop.miss_percent:.2f} %; during the goal "
          f"{goal_rows[0]} of {goal_rows[1]}), {loop.robot['bad_frames']} bad states, "
          f"cpu/tick median {loop.series['cpu']['p50_ms']:.3f} ms mean "
          f"{loop.series['cpu']['mean_ms']:.3f} ms p99 "
          f"{loop.series['cpu']['p99_ms']:.3f} ms; bridge: {wire.states_published} states, "
          f"{wire.commands_received} commands ({wire.commands_superseded} superseded) of "
          f"{loop.robot['commands_sent']} sent, rejected {wire.commands_rejected or 0}, "
          f"replies lost {wire.replies_lost}, overruns {wire.overruns}, CPU "
          f"{wire.cpu_percent:.0f} %; latency received median {wire.received_ms['median']:.2f} "
          f"p99 {wire.received_ms['p99']:.2f} ms, taken median {wire.taken_ms['median']:.2f} p99 "
          f"{wire.taken_ms['p99']:.2f} max {wire.taken_ms['max']:.2f} ms, written median "
          f"{wire.written_ms['median']:.2f} p99 {wire.written_ms['p99']:.2f} ms; quality: "
          f"{_rounded(five_run.as_dict())}; bridge's loop: {loop_scheduling(bridge.output())}; "
          f"controller's loop: {loop_scheduling(controller.output())}")
    # The wire: nothing malformed either way; every command taken was applied, or replaced by
    # a newer one taken in the same physics step.
    assert wire.commands_rejected == {}
    assert loop.robot["bad_frames"] == 0 and loop.robot["commands_refused"] == 0
    assert wire.commands_received == wire.commands_applied + wire.commands_superseded
    assert wire.commands_applied > 0.9 * loop.robot["commands_sent"]
    # Timing (CI bounds: module doc).
    assert loop.series["cpu"]["p50_ms"] <= CPU_MEDIAN_MAX_SHARE * 1e3 / RATE_HZ
    assert loop.miss_percent <= MISS_PERCENT_MAX
    written, received = wire.written_ms["median"], wire.received_ms["median"]
    assert written - loop.series["cpu"]["p50_ms"] <= WRITTEN_OVER_CPU_MAX_MS
    assert received - written <= RECEIVED_OVER_WRITTEN_MAX_MS
    assert wire.taken_ms["median"] - received <= TAKEN_OVER_RECEIVED_MAX_MS
    # Written, then received, then taken at a physics step.
    assert (wire.written_ms["median"] <= wire.received_ms["median"]
            <= wire.taken_ms["median"])
    # Quality, against the truth.
    assert five_run.raised_foot_rms_mm < RAISED_RMS_MAX_MM
    assert five_run.holding_rms_mm < HOLDING_RMS_MAX_MM
    assert five_run.max_tilt_deg < TILT_MAX_DEG
    assert five_run.on_four_feet, five_run.final_foot_forces_n
    estimate = five_run.estimate
    assert 1e3 * estimate["velocity_rms_m_s"] < VELOCITY_RMS_MAX_MM_S
    assert estimate["height_max_mm"] < HEIGHT_MAX_MM
    assert max(estimate["roll_max_deg"], estimate["pitch_max_deg"]) < ROLL_PITCH_MAX_DEG
    # The controller's own account: the goal succeeded, then the stop sat the robot down.
    assert [g["event"] for g in loop.goals] == ["succeeded", "succeeded"]
    assert loop.stop_notes == ["sit ended SUCCEEDED", "damping (at rest)"]


def _rounded(value: object) -> object:
    """``value`` with its floats to 3 significant digits, in nested dicts and lists."""
    if isinstance(value, dict):
        return {key: _rounded(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_rounded(item) for item in value]
    if isinstance(value, float):
        return float(f"{value:.3g}")
    return value


# -- b to e: one bridge, controllers as the scenarios need ------------------------------------


class SharedRun:
    """One bridge for the scenarios b to e, the controller alive now, the truth read live."""

    def __init__(self, run: DdsProcesses, truth: TruthMonitor) -> None:
        self.run = run
        self.truth = truth
        self.bridge = run.bridge(rate_hz=RATE_HZ, log=False)  # the truth is read live
        self.controller: ManagedProcess | None = None

    def ready(self) -> ManagedProcess:
        """A controller running and the robot standing (starting a controller if none)."""
        if self.controller is None or not self.controller.alive:
            self.controller = self.run.controller(rate_hz=RATE_HZ)
        self.wait_standing(timeout_s=10.0)
        return self.controller

    def wait_standing(self, *, timeout_s: float) -> np.ndarray:
        """The truth sample once the robot has stood (feet loaded, base up) for
        :data:`STANDING_HOLD_S`."""
        return self.truth.wait_for(standing, timeout_s=timeout_s, hold_s=STANDING_HOLD_S,
                                   what="the robot standing on four loaded feet")


@pytest.fixture(scope="module")
def shared(tmp_path_factory: pytest.TempPathFactory) -> Iterator[SharedRun]:
    with DdsProcesses(tmp_path_factory.mktemp("dds_shared"),
                      domain_id=private_domain_id(1)) as run, \
            TruthMonitor(run.domain_id, run.interface) as truth:
        state = SharedRun(run, truth)
        yield state
        if state.controller is not None and state.controller.alive:
            assert state.controller.stop() == EXIT_INTERRUPTED, state.controller.tail()
        assert state.bridge.stop() == 0, state.bridge.tail()


@pytest.mark.slow
def test_b_ctrl_c_in_the_client_mid_raise_cancels_and_the_robot_stands(
        shared: SharedRun) -> None:
    """SIGINT to the client during the raise: it cancels the goal, which unwinds (the foot
    down) and ends CANCELED; the truth shows the robot on four loaded feet."""
    shared.ready()
    start = time.monotonic()
    client = shared.run.high_five(height_m=0.4, hold_s=2.0)
    raise_s = _mid_raise(client)
    client.interrupt()
    signalled_s = time.monotonic()
    assert client.wait(15.0) == EXIT_INTERRUPTED, client.tail()
    ended_s = _seconds_since(signalled_s)
    outcome = client_outcome(client.output())
    assert outcome.interrupted and outcome.status == "CANCELED", client.tail()
    assert "ready" not in outcome.phases  # canceled during the raise, before the hold
    assert outcome.phases[-1] == "canceled"
    assert "the robot is back on four feet" in (outcome.message or "")
    record = shared.wait_standing(timeout_s=5.0)
    print(f"\nb. {_seconds_since(start):.1f} s wall; SIGINT {signalled_s - raise_s:.2f} s into "
          f"the raise; client out {ended_s:.2f} s later, {outcome.status}: {outcome.message}; "
          f"truth after: base {base_height_m(record):.3f} m, feet "
          f"{np.round(record['foot_force_n'], 1).tolist()} N")


def test_c_kill_9_of_the_client_mid_goal_ends_the_goal_and_the_robot_stands(
        shared: SharedRun) -> None:
    """SIGKILL to the client during the raise: the controller sees its liveliness lapse,
    cancels the goal and goes idle; the truth shows the robot on four loaded feet."""
    controller = shared.ready()
    start = time.monotonic()
    mark = controller.mark()
    client = shared.run.high_five(height_m=0.4, hold_s=2.0)
    goal_id = client.wait_for_line(r"^Goal accepted with ID: (\S+)").group(1)
    raise_s = _mid_raise(client)
    assert client.kill() == -9
    killed_s = time.monotonic()
    # The controller cancels the goal of a client whose liveliness lapsed (0.5 s lease) ...
    gone = controller.wait_for_line(rf"of goal {goal_id} \(high_five\) is gone .*canceling",
                                    timeout_s=5.0, after=mark)
    gone_s = _seconds_since(killed_s)
    # ... and the goal unwinds: the status line says idle again.
    controller.wait_for_line(r"\| idle \| OK", timeout_s=10.0, after=gone.end())
    idle_s = _seconds_since(killed_s)
    record = shared.wait_standing(timeout_s=5.0)
    print(f"\nc. {_seconds_since(start):.1f} s wall; kill -9 {killed_s - raise_s:.2f} s into "
          f"the raise; controller cancels after {gone_s:.2f} s, idle after {idle_s:.2f} s; "
          f"truth: base {base_height_m(record):.3f} m, feet "
          f"{np.round(record['foot_force_n'], 1).tolist()} N")
    assert gone_s < 2.0  # the lease, its check and a status line


@pytest.mark.slow
def test_e_kill_9_of_the_controller_damps_the_bridge_and_a_new_controller_takes_over(
        shared: SharedRun) -> None:
    """SIGKILL to the standing robot's controller: the bridge damps after its command
    timeout and the robot sinks onto its belly; a new controller stands it up and a high five
    succeeds. (Before d, which ends its controller with Ctrl-C to read its log.)"""
    controller = shared.ready()
    start = time.monotonic()
    mark = shared.bridge.mark()
    assert controller.kill() == -9
    killed_s = time.monotonic()
    damping = shared.bridge.wait_for_line(r"no valid command for .*: motors damping",
                                          timeout_s=5.0, after=mark)
    damping_s = _seconds_since(killed_s)
    down = shared.truth.wait_for(lambda r: base_height_m(r) < 0.15, timeout_s=10.0,
                                 what="the damped robot down on its belly")
    down_s = _seconds_since(killed_s)
    restart_s = time.monotonic()
    shared.controller = restarted = shared.run.controller(rate_hz=RATE_HZ)
    restarted.wait_for_line(r"^the robot is down \(base at 0\.\d+ m\): standing it up")
    shared.bridge.wait_for_line(r"commands resumed: the controller drives the motors",
                                timeout_s=5.0, after=damping.end())
    record = shared.wait_standing(timeout_s=15.0)
    stood_s = _seconds_since(restart_s)
    client = shared.run.high_five(height_m=0.4, hold_s=0.0)
    assert client.wait(GOAL_TIMEOUT_S) == EXIT_SUCCEEDED, client.tail()
    assert client_outcome(client.output()).status == "SUCCEEDED"
    print(f"\ne. {_seconds_since(start):.1f} s wall; bridge damping {damping_s:.2f} s after "
          f"the kill ({damping.group(0)}), base {base_height_m(down):.3f} m after "
          f"{down_s:.2f} s; new controller standing {stood_s:.2f} s after its start (base "
          f"{base_height_m(record):.3f} m); high five SUCCEEDED")
    # The bridge's account between the kill and now: damping, then the new controller.
    events = [text for _, text in bridge_events(shared.bridge.output()[mark:])]
    assert events == ["no valid command for 0.1 s: motors damping (kp 0, kd 5)",
                      "commands resumed: the controller drives the motors again"]
    assert damping_s < 1.0  # 0.1 s timeout, then the line's way to the file


@pytest.mark.slow
def test_d_stalled_bridge_damps_the_controller_aborts_the_goal_and_control_resumes(
        shared: SharedRun) -> None:
    """SIGSTOP to the bridge for 0.3 s during the raise: the controller sends its damped
    fallback within its staleness limit, the goal ends ABORTED naming the fault (the client
    prints it), and once states return the controller stands the robot up (2 s) and control
    resumes (the next high five succeeds); its tick log shows it."""
    controller = shared.ready()
    start = time.monotonic()
    client = shared.run.high_five(height_m=0.4, hold_s=2.0)
    _mid_raise(client)
    shared.bridge.pause()
    time.sleep(STALL_S)  # the stall's length: the scenario, not a synchronisation
    shared.bridge.resume()
    assert client.wait(15.0) == EXIT_NOT_SUCCEEDED, client.tail()
    outcome = client_outcome(client.output())
    assert outcome.status == "ABORTED", client.tail()
    assert "the state stopped being trustworthy" in (outcome.message or "")
    record = shared.wait_standing(timeout_s=5.0)
    # The recovery stand (goals are refused until it SUCCEEDS): the scenario's wait.
    time.sleep(FallbackSettings().stand_s + 0.5)
    # Control resumes: the next goal succeeds.
    follow = shared.run.high_five(height_m=0.4, hold_s=0.0)
    assert follow.wait(GOAL_TIMEOUT_S) == EXIT_SUCCEEDED, follow.tail()
    assert controller.stop() == EXIT_INTERRUPTED, controller.tail()
    shared.controller = None
    stall = _stall_in_log(controller.log_path)
    loop = ControllerFigures.read(controller.report_path)
    print(f"\nd. {_seconds_since(start):.1f} s wall; client: {outcome.status}: "
          f"{outcome.message}; truth after: base {base_height_m(record):.3f} m; stall in the "
          f"controller's log: {stall}; watchdog trips {loop.watchdog_trips}")
    assert stall["gap_s"] > 0.8 * STALL_S
    assert stall["damped_after_s"] <= loop.stale_after_s + DAMP_SLACK_S
    assert stall["damped_share"] == 1.0  # every tick from then until states returned
    assert stall["ok_after_return_s"] < 0.2
    events = [g["event"] for g in loop.goals]
    assert "aborted" in events and events[events.index("aborted") + 1:].count("succeeded") >= 1
    aborted = loop.goals[events.index("aborted")]["detail"]
    assert "the state stopped being trustworthy" in aborted


def _fresh_gaps(log_path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """A controller's tick log: tick times [s], fresh flags, state ticks answered, and the
    row of the last fresh tick before the longest gap between fresh states."""
    with np.load(log_path) as ticks:
        t_s, fresh, state_tick = ticks["t_s"], ticks["fresh"], ticks["state_tick"]
    rows = np.flatnonzero(fresh)
    return t_s, fresh, state_tick, int(rows[int(np.argmax(np.diff(t_s[rows])))])


def _longest_state_gap(log_path: Path) -> str:
    """The longest time without a fresh state in a controller's tick log, and the LowState_
    ticks either side (consecutive: the robot sent nothing; apart: states were lost)."""
    t_s, fresh, state_tick, last = _fresh_gaps(log_path)
    back = last + 1 + int(np.argmax(fresh[last + 1:]))
    return (f"longest time without a fresh state: {1e3 * (t_s[back] - t_s[last]):.1f} ms at "
            f"t {t_s[last] - t_s[0]:.2f} s (LowState_ ticks {state_tick[last]} then "
            f"{state_tick[back]})")


def _stall_in_log(log_path: Path) -> dict[str, float]:
    """The longest run of ticks without a fresh state in a controller's tick log: its length,
    how long after the last fresh state the first FALLBACK (damped) command went out, the
    share of the stall's ticks from then on that were FALLBACK, and how long after states
    returned the status was OK again [s]."""
    t_s, fresh, _, last = _fresh_gaps(log_path)
    back = last + 1 + int(np.argmax(fresh[last + 1:]))  # first fresh tick after the gap
    with np.load(log_path) as ticks:
        status = ticks["control_status"]
        names = [str(n) for n in ticks["control_status_names"]]
    fallback, ok = names.index("FALLBACK"), names.index("OK")
    damped = np.flatnonzero(status[last + 1:back] == fallback)
    first = last + 1 + damped[0] if len(damped) else back
    after = np.flatnonzero(status[back:] == ok)
    return {
        "gap_s": float(t_s[back] - t_s[last]),
        "damped_after_s": float(t_s[first] - t_s[last]) if len(damped) else math.inf,
        "damped_share": float(np.mean(status[first:back] == fallback)) if len(damped) else 0.0,
        "ok_after_return_s": float(t_s[back + after[0]] - t_s[back]) if len(after) else math.inf,
    }
