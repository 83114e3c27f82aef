"""The wire type of the simulator's exact state, on its own DDS topic ``rt/wbc/sim/truth``:
:class:`SimTruth` (filled from the simulator by :func:`sim.sim_truth.sim_truth_record`).

An evaluation topic: ``go2-wbc bridge`` publishes one sample with each ``LowState_`` (same
``tick``), for a measuring tool or a test to compare what a controller estimated and did
with what happened. A controller must never read it: a GO2 has no such topic.

Conventions of the fields (the library's, :mod:`wbc.core.conventions`):

- ``tick``: the ``LowState_.tick`` published with it; ``t_s`` [s]: the simulated time.
- ``q`` (19,): Pinocchio's configuration ``(x, y, z, qx, qy, qz, qw, joints)``: base position
  [m] in the world frame, base orientation ``R_world_base`` as ``(x, y, z, w)`` (scalar
  last, Pinocchio's order; ``LowState_`` carries ``(w, x, y, z)``), then the 12 joint angles
  [rad] in the description's order (legs FL, FR, RL, RR; not the SDK's FR, FL, RR, RL).
- ``v`` (18,): Pinocchio's velocity: base linear [m/s] and angular [rad/s] velocity in the
  base frame, then the joint velocities [rad/s], description order.
- ``foot_position_m`` (4, 3): each foot's centre in the world frame [m], legs FL, FR, RL, RR.
- ``foot_force_n`` (4,): each foot's normal contact force [N], legs FL, FR, RL, RR.

:class:`SimTruth` is the IDL type (what goes on the wire); :class:`SimTruthMessage` is the
same type (de)serialised by a compiled byte copy (:class:`wbc.robot_io.dds.cdr_codec.CdrCodec`),
for the bridge's hot path, holding a :data:`SIM_TRUTH_DTYPE` record::

    reader = DataReader(participant, Topic(participant, SIM_TRUTH_TOPIC, SimTruthMessage))
    for sample in reader.take():
        q = sample.record["q"]
"""

# cyclonedds' IDL annotations are checked at runtime, not by mypy (see go2_types.py).
# mypy: disable-error-code="type-arg, valid-type, assignment"

# No `from __future__ import annotations`: cyclonedds resolves the field types from the real
# annotation objects.
from dataclasses import dataclass, field

import cyclonedds.idl.types as t
import numpy as np
from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import autoid, final

from wbc.robot_io.dds.wire_message import WireMessage

#: The topic the bridge publishes the exact state on.
SIM_TRUTH_TOPIC = "rt/wbc/sim/truth"

#: The record of one sample (C layout, natural alignment), fields as in :class:`SimTruth`.
SIM_TRUTH_DTYPE = np.dtype([
    ("tick", "<u4"), ("t_s", "<f8"), ("q", "<f8", 19), ("v", "<f8", 18),
    ("foot_position_m", "<f8", (4, 3)), ("foot_force_n", "<f8", 4),
], align=True)


@dataclass
@final
@autoid("sequential")
class SimTruth(IdlStruct, typename="wbc.sim.SimTruth"):
    """The simulator's exact state at one published ``LowState_`` (see the module docstring
    for the conventions)."""

    tick: t.uint32 = 0
    t_s: t.float64 = 0.0
    q: t.array[t.float64, 19] = field(default_factory=lambda: [0.0] * 19)
    v: t.array[t.float64, 18] = field(default_factory=lambda: [0.0] * 18)
    foot_position_m: t.array[t.array[t.float64, 3], 4] = field(
        default_factory=lambda: [[0.0] * 3 for _ in range(4)])
    foot_force_n: t.array[t.float64, 4] = field(default_factory=lambda: [0.0] * 4)


class SimTruthMessage(WireMessage):
    """A ``rt/wbc/sim/truth`` sample (:class:`SimTruth` on the wire) holding a
    :data:`SIM_TRUTH_DTYPE` record."""

    idl_type = SimTruth
    dtype = SIM_TRUTH_DTYPE
    __slots__ = ()
