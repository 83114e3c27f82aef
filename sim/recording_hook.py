"""A simulated run into a :class:`~actions.robot.run_recording.RunRecording` (``--mcap``,
``--foxglove``): :class:`RecordingHook`, a loop hook that adds the simulator's truth.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from actions.robot.run_recording import RunRecording, Snapshot, WalkSample
from actions.robot.tick_log import FootTargets
from sim.gait_view import heading_velocities, walking_motion
from wbc.model.description import LEGS
from wbc.model.support_polygon import shrunk_signed_distance

if TYPE_CHECKING:
    from sim.control_loop import ControlLoop
    from wbc.controller.control_output import ControlOutput


class RecordingHook:
    """Every ``recording.decimation``-th tick: the controller's state and command, the
    simulator's true state, foot positions and contact forces, the CoM margin, the swing
    feet's targets, and while a motion walks its commanded velocity beside the measured
    ones (:class:`~actions.robot.run_recording.WalkSample`); then it logs what is queued (a
    simulated run has no deadline to keep).

    Args:
        recording: Where the snapshots go.
        loop: The simulated loop (its truth now: the state the next tick describes).
        phase_of: The goal's phase now (its last feedback).
        leg: The foot the goal moves ("" for none).
    """

    def __init__(self, recording: RunRecording, loop: ControlLoop,
                 phase_of: Callable[[], str], leg: str = ""):
        self.recording = recording
        self.phase_of = phase_of
        self.leg = leg
        self._truth = loop.true_state()
        controller = loop.controller  # once: an isinstance on a protocol costs microseconds
        self._targets = controller if isinstance(controller, FootTargets) else None

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        from sim.episode_metrics import LOADED_FORCE_N

        recording = self.recording
        truth = self._truth
        self._truth = loop.true_state()  # before physics of the next tick: what it sees
        if not recording.due():
            return
        sim, controller = loop.sim, loop.controller
        forces = sim.foot_contact_force_array()
        feet = sim.foot_position_array()
        loaded = feet[forces[:, 2] > LOADED_FORCE_N]
        margin = (shrunk_signed_distance(loaded, sim.data.subtree_com[1])
                  if len(loaded) >= 3 else math.nan)
        stance = tuple(bool(s) for s in controller.schedule.stance)
        targets = np.full((len(LEGS), 3), np.nan)
        for k, leg in enumerate(LEGS):
            if not stance[k] and self._targets is not None:
                target = self._targets.foot_target(leg)
                if target is not None:
                    targets[k] = target
        estimate = None if loop.estimator is None else loop.estimator.estimate
        q, v = np.array(loop.context.q), np.array(loop.context.v)
        walking, walk = walking_motion(loop), None
        if walking is not None:
            walk = walk_sample(walking.commanded_velocity, walking.measured_velocity,
                               stance=stance, q_true=truth[0], v_true=truth[1], forces=forces)
        recording.capture(Snapshot(
            t_s=loop.context.now_s, q=q, v=v,
            tau=np.array(out.tau), foot_target=targets, stance=stance,
            tick_us=out.timings.get("total", math.nan) * 1e6, qp_ok=bool(out.ok),
            status=out.status.name, phase=self.phase_of(),
            estimate_contact=None if estimate is None else np.array(estimate.contact),
            q_true=np.array(truth[0]), v_true=np.array(truth[1]), force_n=forces,
            foot_position=feet, com_margin_m=margin, raised_leg=self.leg, walk=walk))
        recording.drain()


def walk_sample(commanded: np.ndarray, measured: np.ndarray, *, stance: Sequence[bool],
                q_true: np.ndarray | None = None, v_true: np.ndarray | None = None,
                forces: np.ndarray | None = None) -> WalkSample:
    """What a walking motion adds to a snapshot (``/walking``), from one tick's values: the
    same whether the tick is live (:class:`RecordingHook`) or a ``--log`` row replayed
    (:mod:`sim.run_replay`).

    Args:
        commanded: (3,) the motion's commanded velocity, heading frame: forward, lateral
            [m/s], yaw rate [rad/s].
        measured: (3,) the motion's measured velocity, the same frame.
        stance: Per leg (``LEGS`` order), the controller's contact schedule's stance.
        q_true, v_true: (19,), (18,) the simulator's true state at the instant the tick's
            state describes (``None``: a robot's, no truth).
        forces: (4, 3) the feet's measured contact forces [N] (``None``: none measured).
    """
    from sim.episode_metrics import LOADED_FORCE_N

    return WalkSample(
        commanded=np.array(commanded, dtype=float), measured=np.array(measured, dtype=float),
        measured_true=(None if q_true is None or v_true is None
                       else heading_velocities(q_true, v_true)),
        swing_legs=tuple(leg for leg, on in zip(LEGS, stance, strict=True) if not on),
        loaded=None if forces is None else tuple(bool(f > LOADED_FORCE_N)
                                                 for f in forces[:, 2]))
