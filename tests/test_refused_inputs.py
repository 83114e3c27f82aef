"""Inputs the front door used to accept silently or refuse in the wrong words: each one line
naming the argument, the value received and what is valid."""

from __future__ import annotations

import numpy as np
import pytest

from sim.cli import EXIT_USAGE, main
from sim.control_loop import ControlLoop
from wbc import (
    ConfigurationError,
    ControllerConfig,
    Go2Description,
    UnknownNameError,
    WholeBodyController,
)

TRUTH_ONLY = ("not used with --state truth (the controller reads the simulator's exact state: "
              "no estimator runs, no sensor is read); drop it, or use --state estimate "
              "(see 'go2-wbc high-five --help')")


@pytest.mark.slow  # builds a controller: about 2 s
def test_step_before_reset_says_to_call_reset() -> None:
    controller = WholeBodyController()
    q = Go2Description.default().pose("standing")
    with pytest.raises(ConfigurationError) as err:
        controller.step(q, np.zeros(18))
    assert str(err.value) == ("WholeBodyController.step() before reset(): call "
                              "controller.reset(q, v) first, with the robot's state")
    controller.reset(q, np.zeros(18))
    assert controller.step(q, np.zeros(18)).status.name == "OK"


@pytest.mark.parametrize(("changes", "message"), [
    ({"control_period_s": 0.0015},
     ("control_period_s: expected a whole number of physics steps of 0.001 s (e.g. 0.001, "
     "0.002, 0.004 s), received 0.0015 s")),
    ({"control_period_s": float("nan")},
     ("control_period_s: expected a number in (0, 0.1] s, a whole number of physics steps, "
     "received nan")),
    ({"control_period_s": 0},
     ("control_period_s: expected a number in (0, 0.1] s, a whole number of physics steps, "
     "received 0")),
    ({"control_period_s": -1e-3},
     ("control_period_s: expected a number in (0, 0.1] s, a whole number of physics steps, "
     "received -0.001")),
    ({"control_period_s": "1e-3"},
     ("control_period_s: expected a number in (0, 0.1] s, a whole number of physics steps, "
     "received '1e-3'")),
    ({"sensor_seed": "x"},
     ("sensor_seed: expected a whole number >= 0 (the seed of the sensors' noise and biases), "
     "received 'x'")),
    ({"sensor_seed": -1},
     ("sensor_seed: expected a whole number >= 0 (the seed of the sensors' noise and biases), "
     "received -1")),
    ({"sensor_seed": 1.5},
     ("sensor_seed: expected a whole number >= 0 (the seed of the sensors' noise and biases), "
     "received 1.5")),
])
def test_the_simulated_loop_refuses_a_bad_period_or_seed(changes: dict, message: str) -> None:
    with pytest.raises(ConfigurationError) as err:
        ControlLoop.simulated(**changes)
    assert str(err.value) == message


def test_the_simulated_loop_takes_a_numpy_seed_and_a_whole_number_of_steps() -> None:
    loop = ControlLoop.simulated(control_period_s=2e-3, sensor_seed=np.int64(3))
    assert loop.sim.timestep_s == 1e-3 and loop.controller.control_period_s == 2e-3


@pytest.mark.parametrize(("argv", "message"), [
    (["--state", "truth", "--estimator", "kf"], "--estimator kf: "),
    (["--state", "truth", "--estimator", "inekf"], "--estimator inekf: "),
    (["--state", "truth", "--set", "estimator.use_foot_force=false"],
     "--set estimator.use_foot_force=False: "),
    (["--state", "truth", "--sensor-fault", "dropout,3.3,0.02"],
     "--sensor-fault dropout,3.3,0.02: "),
    (["--state", "truth", "--set", "sensors.fault=joint_nan,1,0.5,FR_calf_joint"],
     "--set sensors.fault=joint_nan,1,0.5,FR_calf_joint: "),
])
def test_truth_refuses_what_it_would_ignore(argv: list[str], message: str,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["high-five", *argv])
    assert exc.value.code == EXIT_USAGE
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [f"go2-wbc high-five: error: {message}{TRUTH_ONLY}"]


@pytest.mark.parametrize("attempt", [
    lambda: ControllerConfig.path_of("RANGES"),
    lambda: ControllerConfig().with_values({"shaping.PER_JOINT_TYPE": 1}),
    lambda: ControllerConfig(gains={"RANGES": 1}),
    lambda: ControllerConfig(shaping={"PER_JOINT_TYPE": ("x",)}),
])
def test_the_valid_controller_parameters_are_fields_not_class_tables(attempt) -> None:
    with pytest.raises(UnknownNameError) as err:
        attempt()
    listed = str(err.value).split("; valid ", 1)[1]
    assert "RANGES" not in listed and "PER_JOINT_TYPE" not in listed
    assert "com_kp" in listed or "stance_kp" in listed or "solver" in listed
