"""The behaviours' balance watch: tilt, and the capture point's margin in the ZMP polygon."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from actions.go2.robot_context import CAPTURE_MARGIN_LIMIT_M, RobotContext
from wbc.model.description import LEGS
from wbc.model.support_polygon import SupportPolygon


class StubController:
    """What the watch reads of a controller: its schedule's support feet and minimum force,
    the model's mass, the centre of mass, the feet."""

    total_mass_kg = 15.0
    min_normal_force_n = 10.0

    def __init__(self, rng: np.random.Generator, legs: list[str]):
        self.legs = legs
        self.feet = {leg: np.r_[rng.normal(scale=0.01, size=2) + corner, 0.02]
                     for leg, corner in zip(LEGS, [(0.19, 0.14), (0.19, -0.14), (-0.19, 0.14),
                                                   (-0.19, -0.14)])}
        self.com = np.r_[rng.normal(scale=0.05, size=2), rng.uniform(0.2, 0.35)]
        self.vcom = np.r_[rng.normal(scale=0.3, size=2), 0.0]
        self.schedule = SimpleNamespace(support_legs=lambda: list(self.legs),
                                        min_normal_force_n=self.min_normal_force_n)
        self.description = SimpleNamespace(total_mass=self.total_mass_kg)

    def com_position(self) -> np.ndarray:
        return self.com.copy()

    def com_velocity(self) -> np.ndarray:
        return self.vcom.copy()

    def foot_positions(self) -> np.ndarray:
        return np.array([self.feet[leg] for leg in LEGS])


def reference_margin(c: StubController) -> float:
    """The watch's definition, in plain NumPy."""
    points = np.array([c.feet[leg][:2] for leg in c.legs])
    omega0 = math.sqrt(9.81 / max(c.com[2], 0.05))
    capture = c.com[:2] + c.vcom[:2] / omega0
    shrink = max(0.0, 1.0 - len(c.legs) * c.min_normal_force_n / (c.total_mass_kg * 9.81))
    centre = points.mean(axis=0)
    return SupportPolygon.signed_distance(centre + shrink * (points - centre), capture)


def test_capture_margin_is_the_shrunk_polygon_distance():
    rng = np.random.default_rng(31)
    verdicts = set()
    for i in range(500):
        legs = list(LEGS) if i % 2 else [leg for leg in LEGS if leg != LEGS[i % 8 // 2]]
        controller = StubController(rng, legs)
        context = RobotContext(controller)
        expected = reference_margin(controller)
        assert context.capture_margin_m() == pytest.approx(expected, abs=1e-15)
        verdicts.add(expected < CAPTURE_MARGIN_LIMIT_M)
    assert verdicts == {True, False}


def test_fewer_than_three_support_feet_have_no_margin():
    context = RobotContext(StubController(np.random.default_rng(32), ["FL", "RR"]))
    assert context.capture_margin_m() == -math.inf


def test_tilt_of_a_base_rolled_by_20_degrees():
    context = RobotContext(StubController(np.random.default_rng(33), list(LEGS)))
    q = np.zeros(19)
    q[3], q[6] = math.sin(math.radians(10.0)), math.cos(math.radians(10.0))
    context.observe(0.0, q, np.zeros(18))
    assert context.tilt_deg() == pytest.approx(20.0)
    assert context.balance_problem() == "base tilt 20.0 deg above 12 deg"
