"""What a run did, tick by tick: per-tick arrays, episode metrics, and a plot of them."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from actions.go2.high_five_behaviour import PHASE_NAMES
from sim.gait_view import walking_motion
from sim.run_plot import write_plot  # the plot's home; kept importable from here
from wbc.model.description import JOINT_NAMES, LEGS
from wbc.model.support_polygon import shrunk_signed_distance
from wbc.motions.leg_lift import LiftPhase
from wbc.robot_io.sensor_log import log_row

__all__ = ["RAISED_LEG", "TRACKING_PHASES", "MetricsHook", "TickRecorder", "write_plot"]

if TYPE_CHECKING:
    from sim.control_loop import ControlLoop
    from wbc.controller.control_output import ControlOutput

#: A tick's commanded velocity while nothing walks.
_NO_COMMAND = np.full(3, np.nan)
#: The foot a HighFive goal raises.
RAISED_LEG = "FR"
#: Feedback phases in which the raised foot follows a target (raising, holding, lowering).
TRACKING_PHASES = frozenset(
    PHASE_NAMES[p] for p in (LiftPhase.RAISING, LiftPhase.HOLDING, LiftPhase.LOWERING)
)


class TickRecorder:
    """Per-tick arrays for ``--log`` and ``--plot``: what the controller saw and did, what
    MuJoCo measured during the tick, and the true state the controller's state estimated.

    ``q``, ``v`` are the controller's state (the estimate, unless ``--state truth``);
    ``q_true``, ``v_true`` the simulator's exact state at the same instant;
    ``estimate_contact`` the estimator's contact weight of each foot and ``estimate_flags``
    its fault flags (``wbc.estimation.state_estimator``'s constants; 0 with ``--state truth``);
    ``commanded_velocity`` the walking motion's commanded forward, lateral [m/s] and yaw rate
    [rad/s] (:func:`sim.gait_view.walking_motion`; NaN while nothing walks) and
    ``measured_velocity`` its measured one (the same frame and NaN); ``stance`` (N, 4) the
    controller's contact schedule (``LEGS`` order, True: in stance); the last two with the
    truth and the forces are what a replay's ``/walking`` is built from; when
    estimating, every sensor record the estimator read and its contact schedule
    (:class:`wbc.robot_io.sensor_log.SensorLog` reads them back).
    """

    def __init__(self, phase_of: Callable[[], str], leg: str = RAISED_LEG,
                 loop: ControlLoop | None = None):
        self.phase_of = phase_of
        self.leg = leg
        self._row = LEGS.index(leg)
        self.rows: dict[str, list[Any]] = {k: [] for k in (
            "t_s", "q", "v", "q_true", "v_true", "estimate_contact", "estimate_flags", "tau",
            "foot_target", "foot_position", "phase", "contact_forces", "com_margin_m",
            "qp_ok", "tick_us", "commanded_velocity", "measured_velocity", "stance")}
        #: The truth at the instant the next tick's state describes (before its physics).
        self._truth = None if loop is None else loop.true_state()

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        from sim.episode_metrics import LOADED_FORCE_N

        sim = loop.sim
        phase = self.phase_of()
        # MuJoCo's contacts and positions in data are those of the tick's state (mj_step
        # computes them before integrating), so they line up with q and v below.
        forces = sim.foot_contact_force_array()
        feet = sim.foot_position_array()
        loaded = feet[forces[:, 2] > LOADED_FORCE_N]
        margin = (shrunk_signed_distance(loaded, sim.data.subtree_com[1])
                  if len(loaded) >= 3 else math.nan)
        tracking = phase in TRACKING_PHASES
        target = loop.controller.foot_target(self.leg) if tracking else None
        row = self.rows
        row["t_s"].append(loop.context.now_s)
        row["q"].append(np.array(loop.context.q))
        row["v"].append(np.array(loop.context.v))
        truth = self._truth or (loop.context.q, loop.context.v)
        row["q_true"].append(np.array(truth[0]))
        row["v_true"].append(np.array(truth[1]))
        self._truth = loop.true_state()
        estimate = None if loop.estimator is None else loop.estimator.estimate
        row["estimate_contact"].append(np.ones(len(LEGS)) if estimate is None
                                       else np.array(estimate.contact))
        row["estimate_flags"].append(0 if estimate is None else estimate.flags)
        if loop.estimator is not None:  # what the estimator read (wbc.robot_io.sensor_log)
            for name, value in log_row(loop.estimator.last_sample,
                                       loop.estimator.last_schedule).items():
                row.setdefault(name, []).append(value)
        row["tau"].append(np.array(out.tau))
        row["foot_target"].append(np.full(3, np.nan) if target is None else np.array(target))
        row["foot_position"].append(feet[self._row])
        row["phase"].append(phase)
        row["contact_forces"].append(forces)
        row["com_margin_m"].append(margin)
        row["qp_ok"].append(out.ok)
        row["tick_us"].append(out.timings.get("total", math.nan) * 1e6)
        walking = walking_motion(loop)
        row["commanded_velocity"].append(_NO_COMMAND if walking is None
                                         else np.array(walking.commanded_velocity))
        row["measured_velocity"].append(_NO_COMMAND if walking is None
                                        else np.array(walking.measured_velocity))
        row["stance"].append(np.array(loop.controller.schedule.stance, dtype=bool))

    def arrays(self) -> dict[str, np.ndarray]:
        """The recorded rows as arrays (N = ticks), plus the names that label them."""
        arrays = {k: np.array(v) for k, v in self.rows.items()}
        arrays["phase"] = np.array(self.rows["phase"], dtype=str)
        arrays["joint_names"] = np.array(JOINT_NAMES)
        arrays["legs"] = np.array(LEGS)
        arrays["raised_leg"] = np.array(self.leg)
        return arrays


class MetricsHook:
    """Feeds :class:`sim.episode_metrics.EpisodeMetrics` every tick, from now on.

    Measured on the simulator's true state: the raised foot's error is its true position
    against its target carried from the estimator's world into the simulator's (the frames
    aligned now, at the hook's creation: a goal's start), and the state estimate is compared
    with the truth at the instant it describes.
    """

    def __init__(self, loop: ControlLoop, phase_of: Callable[[], str], leg: str = RAISED_LEG):
        from sim.episode_metrics import EpisodeMetrics, EstimateErrors, FrameAlignment

        self.metrics = EpisodeMetrics(loop.sim, loop.controller.description.effort_limit)
        self.phase_of = phase_of
        self.leg = leg
        self._row = LEGS.index(leg)
        #: The truth at the instant the next tick's state describes (before its physics).
        self._truth = loop.true_state()
        self.alignment = FrameAlignment(loop.context.q, self._truth[0])
        if loop.estimator is not None:
            self.metrics.estimate_errors = EstimateErrors(self.alignment)

    def __call__(self, loop: ControlLoop, out: ControlOutput) -> None:
        phase = self.phase_of()
        error = None
        if phase in TRACKING_PHASES:
            target = self.alignment.point_to_true(loop.controller.foot_target(self.leg))
            foot = loop.sim.foot_position_array()[self._row]
            error = float(np.linalg.norm(foot - target))
        errors = self.metrics.estimate_errors
        if errors is not None:  # the tick's estimate against the truth it saw
            errors.record(loop.context.q, loop.context.v, *self._truth)
        self._truth = loop.true_state()
        self.metrics.record(out, stance_legs=loop.controller.support_legs(), foot_error_m=error,
                            holding=phase == PHASE_NAMES[LiftPhase.HOLDING],
                            controlling=loop.ready)
