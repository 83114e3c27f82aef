"""The command envelope: a combined command scaled to the legs' reach, its changes to the hips'
largest acceleration; each axis alone at its limit untouched."""

import math

import pytest

from wbc.core.errors import ConfigurationError
from wbc.locomotion.command_envelope import CommandEnvelope

#: The GO2's nominal feet from the CoM (heading frame) as Walking.start measures them [m].
OFFSETS = [(0.1934, 0.1625), (0.1934, -0.1625), (-0.1934, 0.1626), (-0.1934, -0.1626)]


@pytest.fixture
def envelope() -> CommandEnvelope:
    # The default trot's 0.275 s stance, a 0.192 m largest step, the lean gain 0.09 s.
    return CommandEnvelope(OFFSETS, stance_s=0.275, max_step_m=0.192, turn_gain_s=0.09)


def test_each_axis_alone_at_its_limit_is_not_scaled(envelope):
    for command in [(1.0, 0.0, 0.0), (0.0, 0.4, 0.0), (0.0, -0.4, 0.0), (0.0, 0.0, 1.2),
                    (0.0, 0.0, -1.2), (0.5, 0.0, 0.3), (-0.5, 0.0, 0.0)]:
        assert envelope.scale(*command) == command


def test_the_step_is_half_a_stance_of_the_fastest_hip_plus_the_lean(envelope):
    assert envelope.step(1.0, 0.0, 0.0) == pytest.approx(0.1375)
    # Turning on the spot: the hip at 0.253 m from the CoM moves at 0.253 m/s per rad/s.
    assert envelope.step(0.0, 0.0, 1.0) == pytest.approx(math.hypot(0.1934, 0.1626) * 0.1375)
    # Forward and turning left: the lean (0.09 s x 1 m/s x 1 rad/s = 0.09 m) points right.
    hips = [((1.0 - y) * 0.1375, x * 0.1375 - 0.09) for x, y in OFFSETS]
    assert envelope.step(1.0, 0.0, 1.0) == pytest.approx(max(math.hypot(*h) for h in hips))


def test_a_combined_fast_command_is_scaled_as_a_whole_onto_the_largest_step(envelope):
    command = (-1.0, 0.26, 0.7)   # fell after 1 to 3 s before the envelope
    assert envelope.step(*command) > envelope.max_step_m
    scaled = envelope.scale(*command)
    assert envelope.step(*scaled) == pytest.approx(envelope.longest_step(scaled[0]), abs=1e-6)
    # Forward, the same command's mirror is scaled less: a longer step is allowed.
    assert envelope.scale(1.0, 0.26, 0.7)[0] > -scaled[0]
    k = scaled[0] / command[0]
    assert 0.7 < k < 0.8
    assert scaled == pytest.approx(tuple(k * c for c in command))  # direction and curvature
    assert envelope.scale(*command) == scaled  # cached, the same


def test_a_change_is_scaled_to_the_hips_largest_acceleration(envelope):
    dt = 1e-3
    # Forward alone at 2 m/s^2: every hip at 2 m/s^2, allowed.
    assert envelope.limit_change(2e-3, 0.0, 0.0, dt=dt) == (2e-3, 0.0, 0.0)
    # With 4 rad/s^2 of yaw the outer hips would accelerate at 2.8 m/s^2: scaled to 2.
    change = envelope.limit_change(2e-3, 0.0, 4e-3, dt=dt)
    assert envelope.hip_speed(*change) == pytest.approx(2.0 * dt)
    assert change[2] / change[0] == pytest.approx(2.0)
    # A stop passes its own deceleration.
    assert envelope.limit_change(3e-3, 0.0, 0.0, dt=dt, accel_mps2=3.0) == (3e-3, 0.0, 0.0)


def test_bad_settings_are_refused_naming_the_field():
    with pytest.raises(ConfigurationError, match="stance_s"):
        CommandEnvelope(OFFSETS, stance_s=0.0, max_step_m=0.2, turn_gain_s=0.09)
    with pytest.raises(ConfigurationError, match="step_share"):
        CommandEnvelope(OFFSETS, stance_s=0.3, max_step_m=0.2, turn_gain_s=0.09,
                        step_share=1.5)
    with pytest.raises(ConfigurationError, match="backward_share"):
        CommandEnvelope(OFFSETS, stance_s=0.3, max_step_m=0.2, turn_gain_s=0.09,
                        backward_share=0.9)


def test_backward_the_step_is_shorter(envelope):
    assert envelope.longest_step(0.5) == envelope.max_step_m == pytest.approx(0.75 * 0.192)
    assert envelope.longest_step(-0.5) == pytest.approx(0.70 * 0.192)
    assert envelope.longest_step(-2.0) == pytest.approx(0.65 * 0.192)
    # Backward 1.0 m/s straight: its 0.1375 m step scaled to where it fits.
    backward = envelope.scale(-1.0, 0.0, 0.0)[0]
    assert envelope.step(backward, 0.0, 0.0) == pytest.approx(
        envelope.longest_step(backward), abs=1e-6)
    assert -0.93 < backward < -0.91
