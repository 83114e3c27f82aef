"""The simulator's exact state now, as a sample of the truth topic ``rt/wbc/sim/truth``:
:func:`sim_truth_record`.

The wire type (:class:`~wbc.robot_io.dds.sim_truth.SimTruth`, its record
:data:`~wbc.robot_io.dds.sim_truth.SIM_TRUTH_DTYPE`, the conventions of its fields) lives
with the GO2's other wire types in :mod:`wbc.robot_io.dds.sim_truth`; its names are
re-exported here for the code that imported them from this module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wbc.robot_io.dds.c_layout import check_record, zero_record
from wbc.robot_io.dds.sim_truth import (
    SIM_TRUTH_DTYPE,
    SIM_TRUTH_TOPIC,
    SimTruth,
    SimTruthMessage,
)

if TYPE_CHECKING:
    from sim.simulator import Go2Simulator

__all__ = ["SIM_TRUTH_DTYPE", "SIM_TRUTH_TOPIC", "SimTruth", "SimTruthMessage",
           "sim_truth_record"]


def sim_truth_record(sim: Go2Simulator, tick: int, *,
                     out: np.ndarray | None = None) -> np.ndarray:
    """The :data:`SIM_TRUTH_DTYPE` record of the simulator's state now.

    Args:
        sim: The simulator.
        tick: The ``LowState_.tick`` it goes with (wraps at 2^32 like it).
        out: A record to fill in place; a new one when not given.

    Raises:
        ConfigurationError: ``out`` is not a :data:`SIM_TRUTH_DTYPE` record.
        NonFiniteError: The simulation diverged (:meth:`Go2Simulator.state`).
    """
    if out is None:
        out = zero_record(SIM_TRUTH_DTYPE)
    else:
        check_record(out, SIM_TRUTH_DTYPE, "out")
    q, v = sim.state()
    out["tick"] = tick % (1 << 32)
    out["t_s"] = sim.time_s
    out["q"] = q
    out["v"] = v
    out["foot_position_m"] = sim.foot_position_array()
    out["foot_force_n"] = sim.foot_normal_forces()
    return out
