"""The simulated loop an :class:`sim.episode.Episode` runs on (:func:`build_loop`), and the
garbage collector kept off start-up's objects while a loop runs
(:func:`startup_objects_frozen`)."""

from __future__ import annotations

import contextlib
import gc
from collections.abc import Iterator
from typing import TYPE_CHECKING

from sim.episode import Episode

if TYPE_CHECKING:
    from sim.control_loop import ControlLoop
    from wbc.controller.balance_controller import BalanceController


@contextlib.contextmanager
def startup_objects_frozen() -> Iterator[None]:
    """Keep what start-up allocated out of the garbage collector's scans while the loop runs.

    Building the loop leaves about 150,000 objects (the models, MuJoCo, numba's compiled
    code); a full collection of them takes about 20 ms, twenty control periods if it came
    inside a tick. The loop's ticks free what they allocate, so full collections are rare,
    but a long run gets one. ``gc.freeze()`` moves them all to a generation no collection
    scans; ``gc.unfreeze()`` gives them back when the block ends (the command line may run
    inside a longer-lived Python process). Do the same around your own loop.
    """
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def build_loop(episode: Episode, controller: BalanceController | None = None) -> ControlLoop:
    """A fresh simulated loop for ``episode``: its plant, rates, sensors, state source,
    estimator, delay, faults and start pose (not settled).

    Args:
        episode: The episode.
        controller: The controller (default: a :class:`wbc.WholeBodyController` with the
            episode's control period and ``controller_params``).
    """
    from sim.control_loop import ControlLoop
    from wbc.controller.whole_body_controller import WholeBodyController

    if controller is None:
        controller = WholeBodyController(episode.controller_config)
    return ControlLoop.simulated(
        pose=episode.start_pose, plant=episode.plant_model,
        control_period_s=episode.control_period_s, physics_timestep_s=episode.timestep_s,
        controller=controller, sensors=episode.sensor_model, sensor_seed=episode.sensor_seed,
        state=episode.state,
        estimator=episode.make_estimator() if episode.state == "estimate" else None,
        command_delay_ticks=episode.command_delay_ticks,
        sensor_faults=list(episode.sensor_faults))
