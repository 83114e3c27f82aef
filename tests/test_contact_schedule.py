"""The contact schedule: modes, bounds, the ramps it moves each tick, LegLift asking for them."""

import numpy as np
import pinocchio as pin
import pytest

from wbc import LegLift, LiftPhase, WholeBodyController
from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.controller_config import ContactSettings
from wbc.core.errors import ConfigurationError, UnknownNameError
from wbc.core.min_jerk import min_jerk
from wbc.model.description import LEGS

DT = 1e-3


def schedule(listener=None) -> ContactSchedule:
    return ContactSchedule(LEGS, ContactSettings(), control_period_s=DT, listener=listener)


def test_a_ramp_is_minimum_jerk_from_its_start_and_ends_at_its_end():
    changes = []
    s = schedule(changes.append)
    s.ramp_normal_force("FR", 0.0, 0.01, from_n=40.0)
    assert s.max_normal_force("FR") == 40.0 and s.is_ramping("FR")  # the next tick uses it
    values = []
    for _ in range(12):
        s.advance()
        values.append(s.max_normal_force("FR"))
    expected = [40.0 * (1.0 - min_jerk(k * DT / 0.01)[0]) for k in range(11)] + [0.0]
    np.testing.assert_allclose(values, expected, atol=1e-12)
    assert values[10] == 0.0 and not s.is_ramping("FR")
    assert changes == ["FR"] * 11  # the request and each tick that moved the bound
    np.testing.assert_array_equal(s.bounds, [250.0, 0.0, 250.0, 250.0])
    assert s.support_legs() == ["FL", "RL", "RR"]


def test_a_ramp_resumed_part_way_takes_up_where_its_curve_is():
    s = schedule()
    s.ramp_normal_force("RL", 100.0, 0.4, from_n=0.0, elapsed_s=0.1)
    assert s.max_normal_force("RL") == pytest.approx(100.0 * min_jerk(0.25)[0])
    s.advance()
    s.advance()
    assert s.max_normal_force("RL") == pytest.approx(100.0 * min_jerk(0.1 / 0.4 + DT / 0.4)[0])


def test_a_set_bound_or_a_mode_change_ends_the_ramp():
    s = schedule()
    s.ramp_normal_force("FR", 0.0, 1.0)
    s.set_max_normal_force("FR", 30.0)
    s.advance()
    s.advance()
    assert s.max_normal_force("FR") == 30.0 and not s.is_ramping("FR")
    s.ramp_normal_force("FR", 0.0, 1.0)
    s.set_swing("FR")
    s.advance()
    s.advance()
    assert s.max_normal_force("FR") == 0.0 and not s.is_stance("FR")
    s.set_stance("FR")
    assert s.stance_legs == list(LEGS) and s.max_normal_force("FR") == 0.0


def test_bad_requests_name_the_argument():
    s = schedule()
    with pytest.raises(ConfigurationError, match=r"^FR max_normal_force_n: expected a value in "
                                                 r"\[0, 250\], received 300$"):
        s.ramp_normal_force("FR", 300.0, 0.4)
    with pytest.raises(ConfigurationError, match=r"^duration_s: expected a value in \(0, inf\], "
                                                 r"received 0$"):
        s.ramp_normal_force("FR", 0.0, 0.0)
    with pytest.raises(UnknownNameError, match="unknown leg 'XX'; valid legs: FL, FR, RL, RR"):
        s.ramp_normal_force("XX", 0.0, 0.4)
    s.set_swing("FR")
    with pytest.raises(ConfigurationError, match=r"^leg: FR is in swing; call set_stance\('FR'\) "
                                                 r"before ramping its bound$"):
        s.ramp_normal_force("FR", 10.0, 0.4)
    with pytest.raises(ConfigurationError, match="at least three feet must stay in stance"):
        s.set_swing("RL")
    assert not s.bounds.flags.writeable  # read in place by the QP, changed by the setters


def test_the_controller_reads_the_schedule_s_bounds_in_its_qp(description):
    controller = WholeBodyController()
    q = description.pose("standing")
    controller.reset(q)
    controller.schedule.ramp_normal_force("FR", 5.0, 0.002, from_n=20.0)
    out = controller.step(q, np.zeros(18))
    assert out.ok and out.forces[1, 2] <= 20.0 + 1e-7
    controller.step(q, np.zeros(18))
    out = controller.step(q, np.zeros(18))  # the ramp has ended
    assert out.ok and out.forces[1, 2] <= 5.0 + 1e-7
    assert controller.schedule.support_legs() == ["FL", "RL", "RR"]


def test_leg_lift_asks_the_schedule_for_ramps_and_never_sets_bounds_each_tick(description,
                                                                              monkeypatch):
    """The README's open-loop lift: LegLift asks for two ramps (unload, reload) and releases
    the bound once; every other change of the bound is the schedule's own, one per tick."""
    controller = WholeBodyController()
    q, v = description.pose("standing"), np.zeros(18)
    controller.reset(q, v)
    calls = []
    schedule = controller.schedule
    for name in ("ramp_normal_force", "set_max_normal_force", "set_swing", "set_stance"):
        method = getattr(schedule, name)

        def recorded(*args, _name=name, _method=method, **kwargs):
            calls.append((_name, args))
            return _method(*args, **kwargs)
        monkeypatch.setattr(schedule, name, recorded)
    lift = LegLift(controller, leg="FR", height_m=0.30, hold_s=0.1)
    t, dt = 0.0, controller.control_period_s
    lift.start(t)
    unloading = []
    while lift.phase is not LiftPhase.DONE:
        phase = lift.advance(t)
        out = controller.step(q, v)
        assert out.ok, out.message
        if phase is LiftPhase.UNLOADING:  # the bound this tick's QP had
            unloading.append(schedule.max_normal_force("FR"))
            assert out.forces[1, 2] <= unloading[-1] + 1e-7
        v = v + out.qdd * dt
        q = pin.integrate(description.model, q, v * dt)
        t += dt
    assert [name for name, _ in calls] == ["ramp_normal_force", "set_swing", "set_stance",
                                           "ramp_normal_force", "set_max_normal_force"]
    assert calls[-1][1] == ("FR", schedule.full_normal_force_n)
    # The unloading bound falls smoothly from the foot's load (each tick's step a small part
    # of it) to nothing, and the foot is released.
    assert abs(len(unloading) - round(lift.timing.unload_s / dt)) <= 1  # the clock's rounding
    assert np.all(np.diff(unloading) <= 1e-12) and unloading[-1] < 1e-4 * unloading[0]
    assert np.max(-np.diff(unloading)) < 0.01 * unloading[0]
    assert schedule.stance_legs == list(LEGS) and schedule.support_legs() == list(LEGS)


def test_the_change_counts_move_when_a_mode_or_the_support_may_have_changed():
    # The controller skips re-reading the modes and the support feet while these stay equal.
    s = schedule()
    modes, support = s.mode_changes, s.support_changes
    s.ramp_normal_force("FR", 0.0, 0.005)  # a bound set: the support may change, no mode
    assert (s.mode_changes, s.support_changes) == (modes, support + 1)
    seen = []
    for _ in range(7):
        before = s.support_changes
        s.advance()
        seen.append(s.support_changes - before)
    # The ramp's first tick uses the bound set; the second leaves 250 N (FR no longer a
    # support foot: counted once); the rest move it below 250 N without a count.
    assert seen == [0, 1, 0, 0, 0, 0, 0] and s.support_legs() == ["FL", "RL", "RR"]
    s.ramp_normal_force("FR", 250.0, 0.003)
    support = s.support_changes
    for _ in range(4):
        s.advance()
    assert s.support_changes == support + 1 and s.support_legs() == list(LEGS)  # reached 250
    modes = s.mode_changes
    s.set_swing("FR")
    s.set_stance("FR")
    s.reset()
    assert s.mode_changes == modes + 3


def test_the_controller_follows_the_support_feet_through_a_ramp(description):
    # A ramped reload makes the foot a support corner again (the polygon's barrier back on),
    # though the controller re-reads the support feet only when the schedule's count moved.
    ctrl = WholeBodyController(description=description)
    q = description.pose("standing")
    ctrl.reset(q)
    v = np.zeros(ctrl.model.nv)
    ctrl.schedule.ramp_normal_force("FR", 0.0, 0.003)
    for _ in range(5):
        ctrl.step(q, v)
    assert ctrl.support_legs() == ["FL", "RL", "RR"]
    assert ctrl.balance.support_barrier.n_edges == 3
    ctrl.schedule.ramp_normal_force("FR", 250.0, 0.003)
    for _ in range(5):
        ctrl.step(q, v)
    assert ctrl.support_legs() == list(LEGS) and ctrl.balance.support_barrier.n_edges == 4
