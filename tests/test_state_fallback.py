"""The loop's fallback: the decaying damping command against time, its settings, the mode log,
and every change of mode on a simulated GO2 (goals refused with the reason meanwhile, the
recovery stand let through, a stop that cannot sit)."""

from __future__ import annotations

import numpy as np
import pytest

from actions import GoalStatus, HighFiveGoal
from actions.go2.go2_interfaces import SitGoal, StandGoal
from actions.go2.high_five_behaviour import ROBOT_NOT_READY
from actions.robot.rest_sequence import Phase, RestSequence
from actions.robot.state_fallback import (
    FallbackSettings,
    LoopMode,
    ModeLog,
    decaying_damping,
)
from sim.control_loop import ControlLoop
from sim.sensor_faults import SensorFault
from tests.test_robustness import torque_beyond_limits
from wbc.controller.control_output import ControlStatus
from wbc.core.errors import ConfigurationError

HELD = np.array([10.0, -4.0, 2.0, 0.0, 6.0, -8.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0])
LIMIT = np.full(12, 23.7)


def test_the_held_torques_ramp_linearly_to_zero_then_only_damping_is_left():
    dq = np.linspace(-1.0, 1.0, 12)
    kd = np.full(12, 80.0)
    kd[3:6] = 1.0  # a leg in the air
    for elapsed, share in [(0.0, 1.0), (0.025, 0.75), (0.05, 0.5), (0.099, 0.01), (0.1, 0.0),
                           (5.0, 0.0)]:
        out = decaying_damping(HELD, dq, elapsed, decay_s=0.1, damping_kd=kd, tau_max=LIMIT,
                               message="stale")
        np.testing.assert_allclose(out.tau_ff, share * HELD, atol=1e-12)
        assert (out.kp == 0.0).all() and (out.q_des == 0.0).all() and (out.dq_des == 0.0).all()
        np.testing.assert_array_equal(out.kd, kd)
        np.testing.assert_allclose(out.tau, np.clip(share * HELD - kd * dq, -LIMIT, LIMIT))
        assert out.status is ControlStatus.FALLBACK and out.message == "stale"
    # After the decay: at most kd |dq| per joint, whatever the held torques were.
    assert (np.abs(out.tau) <= kd * np.abs(dq) + 1e-12).all()
    # A broken velocity reading is taken as zero in ``tau``; no decay time: damping at once.
    out = decaying_damping(HELD, np.full(12, np.nan), 0.0, decay_s=0.0, damping_kd=5.0,
                           tau_max=LIMIT, message="")
    assert (out.tau_ff == 0.0).all() and (out.tau == 0.0).all() and (out.kd == 5.0).all()


def test_settings_are_checked_by_name():
    assert FallbackSettings() == FallbackSettings(decay_s=0.1, damping_kd=80.0,
                                                  swing_damping_kd=1.0, stand_s=2.0)
    with pytest.raises(ConfigurationError,
                       match=r"^decay_s: expected a finite number >= 0, received -0.1$"):
        FallbackSettings(decay_s=-0.1)
    with pytest.raises(ConfigurationError, match=r"^stand_s: expected a finite number >= 0.5"):
        FallbackSettings(stand_s=0.1)
    with pytest.raises(ConfigurationError, match=r"^damping_kd: .* received nan$"):
        FallbackSettings(damping_kd=float("nan"))


def test_the_mode_log_keeps_the_changes_and_a_decision_at_the_start_replaces_the_first():
    log = ModeLog(LoopMode.CONTROLLING, "", 0.0)
    log.enter(LoopMode.WAITING, "no sample", 0.0)  # decided at the start
    log.enter(LoopMode.WAITING, "still none", 0.5)  # a new reason: no change logged
    log.enter(LoopMode.RECOVERING, "back", 1.0)
    assert [(t.t_s, t.mode, t.reason) for t in log.transitions] == [
        (0.0, LoopMode.WAITING, "no sample"), (1.0, LoopMode.RECOVERING, "back")]
    assert log.summary() == "1.00 s RECOVERING (back)"
    assert log.transitions[1].as_dict() == {"t_s": 1.0, "mode": "RECOVERING", "reason": "back"}


def refused(loop: ControlLoop, action: str, goal) -> str:
    """The rejection message of ``goal`` sent now (its code checked)."""
    future = loop.client(action).send_goal_async(goal)
    loop.spin_once()
    handle = future.result()
    assert not handle.accepted, f"{action} accepted"
    assert handle.rejection.code == ROBOT_NOT_READY
    return handle.rejection.message


def spin_until(loop: ControlLoop, mode: LoopMode, limit_s: float) -> None:
    end = loop.robot.time_s + limit_s
    while loop.fallback.mode is not mode:
        assert loop.robot.time_s < end, f"not {mode.name} within {limit_s} s"
        loop.spin_once()


@pytest.fixture(scope="module")
def loop() -> ControlLoop:
    # No sample for 50 ms from the start; then the state freezes 0.5 s into the recovery
    # stand, for 50 ms.
    return ControlLoop.simulated(sensor_faults=[SensorFault("dropout", 0.0, 0.05),
                                                SensorFault("stale", 0.55, 0.05)])


def test_every_change_of_mode_refuses_goals_until_the_robot_is_stood_up(loop):
    # WAITING from the start: damping, goals refused with the reason.
    assert loop.fallback.mode is LoopMode.WAITING and not loop.ready
    assert refused(loop, "high_five", HighFiveGoal(target_height=0.3)) == (
        "robot not able: waiting for a sensor sample to start the state estimator from: no "
        "sensor sample")
    assert loop.last_output.status is ControlStatus.FALLBACK and (loop.last_output.kp == 0).all()
    # RECOVERING: the estimator started; its stand is let through, a user's goal is not.
    spin_until(loop, LoopMode.RECOVERING, 0.1)
    assert loop.fallback.log.transitions[-1].t_s == pytest.approx(0.05, abs=1.5e-3)
    assert loop.fallback.log.reason == "the state estimator started: standing the robot up"
    assert refused(loop, "stand", StandGoal(duration_s=1.0)) == (
        "robot not able: standing up after a time without trustworthy state")
    (stand,) = loop.runner.active_goals()
    assert stand.label.endswith("(stand)")
    # FALLBACK: the state freezes during the stand, which ends ABORTED with the reason.
    spin_until(loop, LoopMode.FALLBACK, 0.6)
    assert stand.status is GoalStatus.ABORTED
    assert refused(loop, "sit", SitGoal(duration_s=1.0)).startswith(
        "robot not able: no trustworthy state (state estimate: no trustworthy sensor sample "
        "for 11 ms (limit 10 ms): stale sample (tick ")
    # RECOVERING again when it is fresh, then CONTROLLING once the new stand SUCCEEDED.
    spin_until(loop, LoopMode.RECOVERING, 0.1)
    assert loop.fallback.log.reason == ("trustworthy state back, the state estimator started "
                                        "again: standing the robot up")
    spin_until(loop, LoopMode.CONTROLLING, 2.1)
    assert [t.mode for t in loop.fallback.log.transitions] == [
        LoopMode.WAITING, LoopMode.RECOVERING, LoopMode.FALLBACK, LoopMode.RECOVERING,
        LoopMode.CONTROLLING]
    assert loop.ready and loop.context.goal_refusal == ""
    assert loop.last_output.status is ControlStatus.OK


def test_a_stop_without_trustworthy_state_damps_and_says_the_robot_is_not_at_rest():
    loop = ControlLoop.simulated(sensor_faults=[SensorFault("dropout", 0.0, 1.0)])
    rest = RestSequence(loop)
    rest.request_stop("test")
    while rest.step(loop.robot.time_s) < Phase.DAMPING:
        assert loop.robot.time_s < 0.1
        loop.spin_once()
    assert rest.notes == [
        ("sit refused (waiting for a sensor sample to start the state estimator from: no "
        "sensor sample)"), "damping (not at rest: the robot could not be sat down)"]


def test_a_sit_that_ends_aborted_is_named_and_the_robot_is_not_said_to_be_at_rest():
    loop = ControlLoop.simulated(sensor_faults=[SensorFault("stale", 0.3, 1.0)])
    rest = RestSequence(loop)
    rest.request_stop("test")
    while rest.step(loop.robot.time_s) < Phase.DAMPING:
        assert loop.robot.time_s < 0.4
        loop.spin_once()
    sat, damped = rest.notes
    assert sat.startswith("sit ended ABORTED: the state stopped being trustworthy (state "
                          "estimate: no trustworthy sensor sample for 11 ms (limit 10 ms): "
                          "stale sample (tick ")
    assert damped.startswith("damping (not at rest: base at 0.")


def test_a_recovery_stand_that_fails_is_sent_again():
    loop = ControlLoop.simulated(sensor_faults=[SensorFault("dropout", 0.0, 0.02)])
    spin_until(loop, LoopMode.RECOVERING, 0.1)
    loop.spin_once()  # the stand sent in the last tick starts in this one
    (first,) = loop.runner.active_goals()
    # One tick whose command a driver would refuse (the guard's safe command): the stand,
    # which aborts on a controller fault, ends ABORTED.
    torque_beyond_limits(loop, 1)
    loop.spin_for(0.005)
    assert first.status is GoalStatus.ABORTED
    assert loop.fallback.mode is LoopMode.RECOVERING
    (second,) = loop.runner.active_goals()
    assert second.goal_id != first.goal_id and second.label.endswith("(stand)")
    spin_until(loop, LoopMode.CONTROLLING, 2.1)
    assert second.status is GoalStatus.SUCCEEDED
