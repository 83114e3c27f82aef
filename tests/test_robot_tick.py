"""The robot loop's one tick: the simulated loop and the wall-clock loop run the same stages
and send the same commands from the same recorded states; a robot's optional capabilities
are found by their declared protocols; the behaviours come from the loop's caller."""

from __future__ import annotations

import numpy as np
import pytest

from actions.go2.go2_loop_behaviours import GO2_BEHAVIOURS, Go2Behaviours
from actions.robot.control_loop import ControlLoop
from actions.robot.dds_robot import DdsRobotCounters
from actions.robot.realtime_loop import RealtimeLoop
from actions.robot.recorded_robot import RecordedRobot
from actions.robot.rest_sequence import Phase
from actions.robot.robot_capabilities import (
    AnswersTicks,
    CountsSkips,
    DescribesStream,
    ReportsStats,
    StalenessLimited,
    StateWaiting,
)
from actions.robot.robot_loop import RobotLoop
from actions.robot.robot_tick import Stage, StageTimes
from tests.synthetic_records import LOADED, pose, record
from wbc.controller.whole_body_controller import WholeBodyController
from wbc.robot_io.sensor_log import SensorLog, log_row

PERIOD_S = 1e-3
TICKS = 120
#: Ticks whose sample never came (single gaps: shorter than any staleness limit).
GAPS = (40, 41, 90)


class StageLog:
    """A tick timer that keeps the order of the calls it gets."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def start(self) -> None:
        self.calls.append("start")

    def mark(self, stage: Stage) -> None:
        self.calls.append(stage.name)


class FakeClock:
    """A monotonic clock that moves only when slept on."""

    def __init__(self) -> None:
        self.t = 50.0

    def __call__(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.t += seconds


def recorded_log() -> SensorLog:
    """A GO2 standing still for :data:`TICKS` ticks at 1 kHz, no sample at :data:`GAPS`."""
    q = pose()
    rows = [log_row(None if k in GAPS else record(q, tick=k + 1, period_s=PERIOD_S), LOADED)
            for k in range(TICKS)]
    return SensorLog.from_rows(rows)


def wall_clock(loop: RobotLoop, **kwargs) -> RealtimeLoop:
    clock = FakeClock()
    return RealtimeLoop(loop, rate_hz=1.0 / PERIOD_S, clock=clock, sleep=clock.sleep,
                        spin_s=0.0, **kwargs)


@pytest.fixture(scope="module")
def both_loops():
    """The same recording through the simulated loop's spin and the wall-clock loop's tick."""
    log = recorded_log()
    simulated = ControlLoop(RecordedRobot(log), WholeBodyController())
    stages = StageLog()
    for _ in range(TICKS - 1):  # the loop was built from the first sample
        simulated.tick(stages)
    walled = ControlLoop(RecordedRobot(log), WholeBodyController())
    rt = wall_clock(walled)
    rt.start()
    for _ in range(TICKS - 1):
        rt.tick()
    return simulated, rt, stages


def test_both_loops_send_the_same_commands_from_the_same_recorded_states(both_loops):
    simulated, rt, _ = both_loops
    sent = simulated.robot.robot.commands
    walled = rt.loop.robot.robot.commands
    assert len(sent) == len(walled) == TICKS - 1
    for k, (a, b) in enumerate(zip(sent, walled)):
        for name in ("q_des", "dq_des", "kp", "kd", "tau_ff"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name),
                                          err_msg=f"tick {k}: {name}")
    assert rt.stats.ticks == TICKS - 1 and rt.stats.no_fresh_state == len(GAPS)
    assert rt.stats.watchdog_trips == 0 and rt.rest.phase is Phase.RUNNING
    assert simulated.ready and rt.loop.ready


def test_every_tick_runs_the_stages_in_order(both_loops):
    _, rt, stages = both_loops
    one_tick = ["start", *(stage.name for stage in Stage)]
    assert one_tick == ["start", "READ", "ESTIMATE", "ACTIONS", "CONTROLLER", "GUARD",
                        "WRITE", "RELAY", "HOOKS"]
    assert stages.calls == one_tick * (TICKS - 1)
    # The wall-clock loop's series come from the same stages, each timed.
    summary = rt.stats.summary()
    for series in ("read", "actions", "controller", "write", "tick", "latency"):
        assert summary[series]["max_ms"] > 0.0, series
    assert summary["tick"]["max_ms"] >= summary["latency"]["max_ms"]


def test_a_filters_command_replaces_the_decision_and_skips_the_hooks():
    log = recorded_log()
    loop = ControlLoop(RecordedRobot(log), WholeBodyController())
    hooked: list[int] = []
    loop.hooks.append(lambda _loop, _out: hooked.append(1))
    rt = wall_clock(loop)
    damping = rt.rest.damping

    class Damp:
        def sensed(self, now_s: float, fresh: bool):
            return damping

        def stale(self, now_s: float) -> str:
            raise AssertionError("no decision: nothing asks whether the state is stale")

    stages = StageLog()
    ticks = loop.runner.tick_count
    assert loop.tick(stages, filters=(Damp(),)) is None
    assert stages.calls == ["start", *(stage.name for stage in Stage)]
    assert loop.runner.tick_count == ticks and not hooked
    np.testing.assert_array_equal(loop.robot.robot.commands[-1].kd, damping.kd)
    assert loop.tick() is not None and hooked == [1] and loop.runner.tick_count == ticks + 1


def test_stage_times_measure_from_the_previous_stages_end():
    clock = iter([1.0, 1.5, 3.0, 3.25, 3.5, 4.0, 4.5, 5.0, 6.0])
    times = StageTimes(lambda: next(clock))
    times.start()
    for stage in Stage:
        times.mark(stage)
    assert times.seconds(Stage.READ) == 0.5
    assert times.seconds(Stage.ESTIMATE) == 1.5
    assert times.seconds(Stage.ACTIONS, Stage.GUARD) == 1.0
    assert times.seconds(Stage.HOOKS) == 1.0


# -- capabilities: declared by protocol, not probed -----------------------------------------


class DdsLikeRobot(RecordedRobot):
    """A recorded robot with every optional capability a DdsRobot has."""

    def __init__(self, log: SensorLog) -> None:
        super().__init__(log)
        self.counters = DdsRobotCounters(ticks_skipped=7)
        self.waits: list[float] = []

    @property
    def stale_after_s(self) -> float:
        return 0.04

    @property
    def answer_tick(self) -> int:
        return 1234

    def stale_reason(self) -> str:
        return "the same bytes each time"

    def wait_for_new_state(self, timeout_s: float) -> bool:
        self.waits.append(timeout_s)
        return True

    def stats(self) -> dict[str, int]:
        return {"states_used": 3}


#: A DDS domain of its own (nothing is published: a dry run).
DDS_DOMAIN = 173
CAPABILITIES = (StateWaiting, CountsSkips, StalenessLimited, DescribesStream, AnswersTicks,
                ReportsStats)


def test_a_dds_robot_declares_every_capability():
    from actions.robot.dds_robot import DdsRobot

    robot = DdsRobot(domain_id=DDS_DOMAIN, interface="lo", dry_run=True)
    try:
        assert [c.__name__ for c in CAPABILITIES if not isinstance(robot, c)] == []
    finally:
        robot.close()


def test_a_robot_without_the_optional_capabilities_runs_on_the_loops_defaults():
    robot = RecordedRobot(recorded_log())
    assert not any(isinstance(robot, capability) for capability in CAPABILITIES)
    loop = ControlLoop(robot, WholeBodyController())
    rt = wall_clock(loop)
    # No limit of its own: the estimator's; no state to wait for: no alignment.
    assert rt.stale_after_s == loop.estimator.config.trust_timeout_s
    for _ in range(5):
        rt.tick()
    report = rt.report()
    assert report["align"]["active"] is False and report["align"]["timeouts"] == 0
    assert report["robot"] == {} and report["state_ticks_skipped"] == 0


def test_a_robot_that_declares_its_capabilities_has_them_used():
    robot = DdsLikeRobot(recorded_log())
    assert all(isinstance(robot, capability) for capability in CAPABILITIES)
    loop = ControlLoop(robot, WholeBodyController())
    rt = wall_clock(loop)
    assert rt.stale_after_s == loop.estimator.config.trust_timeout_s == 0.04
    for _ in range(5):
        rt.tick()
    assert robot.waits == [0.0] * 5  # the state was there at each deadline
    robot.counters.ticks_skipped += 2
    report = rt.report()
    assert report["align"]["active"] is True
    assert report["robot"] == {"states_used": 3} and report["state_ticks_skipped"] == 2
    assert rt.watchdog.stale(rt.loop.robot.time_s + 1.0).endswith(
        "(limit 40 ms); the same bytes each time")


# -- behaviours: the caller's -------------------------------------------------------------


class SpyBehaviours(Go2Behaviours):
    """The GO2's behaviours, keeping the goals the loop asks for."""

    def __init__(self) -> None:
        self.asked: list[tuple[str, float]] = []

    def sit_goal(self, duration_s: float):
        self.asked.append(("sit", duration_s))
        return super().sit_goal(duration_s)


def test_the_generic_loop_takes_its_behaviours_from_the_caller():
    assert ControlLoop(RecordedRobot(recorded_log()),
                       WholeBodyController()).behaviours is GO2_BEHAVIOURS
    behaviours = SpyBehaviours()
    loop = RobotLoop(RecordedRobot(recorded_log()), WholeBodyController(),
                     behaviours=behaviours)
    assert loop.behaviours is behaviours
    assert sorted(loop.runner.server_names) == sorted(
        ControlLoop(RecordedRobot(recorded_log()), WholeBodyController()).runner.server_names)
    rt = wall_clock(loop)
    rt.request_stop("the test is over")
    rt.tick()  # no goal to unwind: the loop's own sit goal is sent
    assert behaviours.asked == [("sit", rt.rest.settings.sit_s)]
    assert rt.rest.phase is Phase.SITTING
