"""Closed loop in MuJoCo at 1 kHz: stand, and lift a foot through every phase and back.

The controller reads the state estimated from the simulated sensors; every bound is
measured on the simulator's truth.
"""

import numpy as np
import pytest

from sim.control_loop import ControlLoop
from tests.closed_loop import run_lift, settle
from tests.sweeps import quick_first
from wbc import LegLift, LiftPhase
from wbc.core.errors import ConfigurationError, ReachabilityError, UnknownNameError

ALL_PHASES = [LiftPhase.SHIFTING, LiftPhase.UNLOADING, LiftPhase.RAISING, LiftPhase.HOLDING,
              LiftPhase.LOWERING, LiftPhase.RELOADING, LiftPhase.SHIFTING_BACK, LiftPhase.DONE]


def standing_loop() -> ControlLoop:
    loop = ControlLoop.simulated()
    settle(loop, 0.01)
    return loop


def test_stands_five_seconds_with_drift_under_5_mm():
    loop = ControlLoop.simulated()
    settle(loop, 0.2)
    start = loop.true_state()[0][:3]
    settle(loop, 5.0)
    assert np.linalg.norm(loop.true_state()[0][:3] - start) < 0.005
    assert loop.controller.failures == 0


@pytest.fixture(scope="module")
def high_five():
    return run_lift("FR", height_m=0.40, hold_s=2.0)


def test_high_five_goes_through_every_phase(high_five):
    summary, _, controller, lift, phases, _ = high_five
    assert phases == ALL_PHASES
    assert lift.progress == 1.0
    assert controller.stance_legs == ["FL", "FR", "RL", "RR"]
    assert not summary.fell


def test_high_five_quality(high_five):
    s = high_five[0]
    assert s.qp_failures == 0
    assert s.raised_foot_rms_mm <= 5.0
    assert s.holding_rms_mm <= 2.0
    assert s.stance_sliding_max_mm <= 2.0
    # The feet are spheres: they roll (their centres move and come back) as the legs tilt,
    # about 0.07 mm per mm of body shift; the 7 cm-deep shift that absorbs pushes costs ~7 mm.
    assert s.stance_travel_max_mm <= 8.0
    assert s.min_stance_normal_force_n >= 5.0
    assert s.max_torque_fraction <= 0.9
    assert s.max_torque_jump_nm <= 1.0
    assert s.min_com_margin_mm > 0.0


def test_high_five_reaches_its_target_in_front_of_the_shoulder(high_five):
    _, loop, _, lift, _, _ = high_five
    assert lift.foot_target[2] == pytest.approx(0.40)
    shoulder = lift.shoulder_while_holding
    assert lift.foot_target[0] > shoulder[0] + 0.1
    assert abs(lift.foot_target[1] - shoulder[1]) < 0.02
    # Back on the ground, loaded, where it started.
    forces = loop.sim.foot_contact_forces()
    assert forces["FR"][2] > 30.0
    assert np.linalg.norm(loop.sim.foot_positions()["FR"][:2] - lift.foot_ground[:2]) < 0.006


# One leg and one instant in the quick stage (RL: a hind leg; 2.0 s: in the raise); the others in
# the slow one.
@pytest.mark.parametrize("leg", quick_first(["FL", "RL", "RR"], lambda leg: leg == "RL"))
def test_any_leg_can_be_raised(leg):
    s, _, _, _, phases, _ = run_lift(leg, height_m=0.25, hold_s=0.2)
    assert phases == ALL_PHASES
    assert not s.fell and s.qp_failures == 0
    assert s.raised_foot_rms_mm <= 5.0
    assert s.min_stance_normal_force_n >= 5.0


@pytest.mark.parametrize("at_s", quick_first([0.5, 1.2, 2.0, 3.5], lambda at_s: at_s == 2.0))
def test_interrupted_lift_returns_to_four_loaded_feet_within_1_5_s(at_s):
    s, loop, _, lift, _, interrupted_in = run_lift("FR", hold_s=2.0, interrupt_at_s=at_s)
    assert interrupted_in in (LiftPhase.SHIFTING, LiftPhase.UNLOADING, LiftPhase.RAISING,
                              LiftPhase.HOLDING)
    assert not s.fell and s.qp_failures == 0
    assert lift.interrupted and lift.phase is LiftPhase.DONE
    # The unwind is bounded: it ended within 1.5 s of the request (plus the 0.3 s settle).
    assert loop.sim.time_s - 0.3 - at_s <= 1.5 + 1e-9
    assert loop.sim.foot_contact_forces()["FR"][2] >= 30.0


def test_lift_validation():
    loop = ControlLoop.simulated()
    controller = loop.controller
    with pytest.raises(ConfigurationError,
                       match=r"height_m: expected a value in \[0.1, 0.5\], received 0.7"):
        LegLift(controller, height_m=0.7)
    with pytest.raises(UnknownNameError, match="unknown leg 'XL'"):
        LegLift(controller, leg="XL")
    with pytest.raises(ConfigurationError,
                       match=r"forward_m: expected a value in \[-0.1, 0.3\], received 0.5"):
        LegLift(controller, forward_m=0.5)
    # The highest, farthest allowed target is still within the leg's reach.
    lift = LegLift(controller, height_m=0.5, forward_m=0.3, lateral_m=0.15)
    settle(loop, 0.01)
    lift.start(loop.sim.time_s)
    assert np.linalg.norm(lift.foot_target - controller.shoulder_position("FR")) < 0.40


def test_unreachable_foot_target_is_refused_by_the_controller():
    controller = standing_loop().controller
    with pytest.raises(ReachabilityError, match="from the FR shoulder; reachable: at most 0.40 m"):
        controller.set_foot_target("FR", controller.shoulder_position("FR") + [0.3, 0.0, 0.3])
    assert controller.stance_legs == ["FL", "FR", "RL", "RR"]  # nothing half-done
