"""Walking's contract on a controller fed a fixed state (open loop, no simulator): its
checks, the order of the contact switches, early and late touch-downs, and the stop."""

import numpy as np
import pytest

from wbc import WholeBodyController
from wbc.core.errors import ConfigurationError
from wbc.locomotion import GaitParameters, VelocityLimits, Walking, WalkPhase

pytestmark = pytest.mark.slow  # the controller's reset loads its compiled programs


@pytest.fixture(scope="module")
def controller():
    return WholeBodyController()


def standing(controller):
    q = controller.description.pose("standing")
    controller.reset(q.copy())
    return q


def run(walking, controller, q, seconds, t0=0.0, on_tick=None):
    """Advance and step every tick on the fixed state ``q``; returns the end time."""
    v = np.zeros(18)
    t = t0
    for _ in range(round(seconds / controller.control_period_s)):
        walking.advance(t)
        controller.step(q, v)
        if on_tick:
            on_tick(t)
        t += controller.control_period_s
    return t


def test_checks_name_the_field(controller):
    with pytest.raises(ConfigurationError, match="controller: walking needs a "
                                                 "WholeBodyController.*received object"):
        Walking(object())
    walking = Walking(controller, limits=VelocityLimits(forward_mps=0.8))
    with pytest.raises(ConfigurationError, match="call start"):
        walking.advance(0.0)
    with pytest.raises(ConfigurationError, match=(
            r"forward_mps: expected a velocity in \[-0.8, 0.8\] m/s, received 0.9")):
        walking.set_velocity(0.9, 0.0, 0.0)
    assert not walking.target_velocity.any()  # nothing changed
    assert walking.phase is None


def test_start_needs_four_feet_in_stance(controller):
    standing(controller)
    controller.schedule.set_swing("FR")
    with pytest.raises(ConfigurationError, match=r"all four feet in stance, stance now: "
                                                 r"\['FL', 'RL', 'RR'\]"):
        Walking(controller).start(0.0)


def test_trot_switches_diagonal_pairs_through_the_ramps(controller):
    q = standing(controller)
    walking = Walking(controller)
    walking.start(0.0)
    assert walking.phase is WalkPhase.STARTING and controller.schedule.min_stance == 2
    seen = []

    def record(t):
        swing = walking.swing_legs
        if not seen or seen[-1][1] != swing:
            seen.append((round(t, 3), swing))

    end = run(walking, controller, q, 0.5, on_tick=record)
    # FR and RL unload for one transfer (0.04 s) and leave; on a fixed state their feet never
    # leave the ground, so each lands early, at half its swing; then FL and RR go.
    assert [s for _, s in seen] == [(), ("FR", "RL"), (), ("FL", "RR"), ()]
    assert seen[1][0] == pytest.approx(0.04, abs=3e-3)
    assert seen[2][0] - seen[1][0] == pytest.approx(0.1125, abs=3e-3)  # half the 0.225 s swing
    assert walking.phase is WalkPhase.WALKING
    assert 0.0 <= walking.gait_phase < 1.0
    walking.request_stop(end)
    assert walking.phase is WalkPhase.STOPPING
    assert not walking.commanded_velocity.any() or walking.target_velocity.tolist() == [0, 0, 0]
    run(walking, controller, q, 1.0, t0=end)
    assert walking.phase is WalkPhase.DONE
    assert controller.stance_legs == ["FL", "FR", "RL", "RR"]
    assert controller.support_legs() == ["FL", "FR", "RL", "RR"]  # fully loaded
    assert controller.schedule.min_stance == 3


def test_footholds_while_swinging_follow_the_command(controller):
    q = standing(controller)
    walking = Walking(controller, gait=GaitParameters(period_s=0.5, duty_factor=0.6))
    walking.start(0.0)
    walking.set_velocity(0.5, 0.0, 0.0)
    footholds = {}

    def record(t):
        footholds.update({leg: walking.footholds[leg].copy() for leg in walking.swing_legs})

    run(walking, controller, q, 0.1, on_tick=record)
    assert set(footholds) == {"FR", "RL"}
    feet = controller.foot_positions()
    for leg, i in (("FR", 1), ("RL", 2)):
        # Ahead of where the foot stands (the command), on the ground (3 mm pressed in).
        assert footholds[leg][0] > feet[i, 0] + 0.03
        assert footholds[leg][2] == pytest.approx(feet[i, 2] - 0.003, abs=1e-3)


def test_late_touchdown_keeps_lowering_and_holds_the_clock(controller):
    # Once FR is in the air its knee is bent on the fixed state: its foot stays 3 cm above
    # the ground it left, whatever the walk asks; it is late, lowered for LATE_MAX_S (the
    # gait clock held meanwhile), then set down.
    q = standing(controller)
    calf = 7 + controller.description.leg_joint_indices("FR")[2]
    walking = Walking(controller)
    walking.start(0.0)
    states, clocks = [], []

    def record(t):
        states.append(walking._legs["FR"].name)
        clocks.append(walking.gait_time_s)
        if states[-1] == "SWING":
            q[calf] = -1.65

    run(walking, controller, q, 0.45, on_tick=record)
    late = [i for i, s in enumerate(states) if s == "LATE"]
    assert late, states[::20]
    assert len(late) == pytest.approx(150, abs=3)  # LATE_MAX_S at 1 kHz
    assert clocks[late[-1]] == pytest.approx(clocks[late[0]], abs=2e-3)  # the clock held
    assert states[late[-1] + 1] == "STANCE"
    # It went late at the end of its swing, not before (0.04 s unloading, 0.225 s swing).
    assert late[0] * controller.control_period_s == pytest.approx(0.265, abs=3e-3)


def test_a_non_finite_reference_is_refused_not_written(controller):
    # The compiled tick writes the tasks' references only after their setters' checks: a
    # non-finite CoM or swing-foot target is left unwritten, and the setter's error raised.
    q = standing(controller)
    walking = Walking(controller)
    walking.start(0.0)
    end = run(walking, controller, q, 0.06)  # FR and RL in the air
    assert walking.swing_legs == ("FR", "RL")
    foot = controller.foot_tasks["FR"].reference.copy()
    walking._starts[1, 0] = np.nan  # FR's lift-off point: its path is not finite
    with pytest.raises(ConfigurationError, match="FR_foot target"):
        walking.advance(end)
    np.testing.assert_array_equal(controller.foot_tasks["FR"].reference, foot)
    com = controller.com_task.reference.copy()
    walking._com_ref[1] = np.inf
    with pytest.raises(ConfigurationError, match="ComTask.target"):
        walking.advance(end + 0.001)
    np.testing.assert_array_equal(controller.com_task.reference, com)
