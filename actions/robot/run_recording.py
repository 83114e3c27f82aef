"""A run recorded off the control tick's path: :class:`RunRecording` copies a
:class:`Snapshot` every few ticks into a bounded queue (dropping, and counting, what does not
fit) and turns the queue into messages on its :class:`~actions.robot.run_channels.RunChannels`
when there is time (:meth:`RunRecording.drain`).

The tick pays for the copy only (a few small arrays, about 10 us every ``decimation`` ticks);
the messages (about 0.3 ms a snapshot: 14 transforms, 12 joints, markers, JSON) are built
after the command is written, in the time left before the next deadline.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from foxglove.messages import (
    ArrowPrimitive,
    Color,
    FrameTransform,
    FrameTransforms,
    JointState,
    JointStates,
    LinePrimitive,
    LinePrimitiveLineType,
    Log,
    LogLevel,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    Vector3,
)

from actions.robot.joint_frames import JointFrames
from actions.robot.run_channels import RunChannels
from wbc.core.errors import ConfigurationError
from wbc.model.description import JOINT_NAMES, LEGS

#: Snapshots a second of robot time, unless given (the state, transforms, plots, markers).
DEFAULT_RATE_HZ = 50.0
#: Snapshots the queue holds before new ones are dropped.
QUEUE_SNAPSHOTS = 512
#: Seconds of robot time between repeats of the URDF on ``/robot_description``.
DESCRIPTION_PERIOD_S = 1.0
#: Factor on a step's expected time each time it did not fit (so an outlier fades).
SKIP_DECAY = 0.95
#: Log levels by name.
LEVELS = {"info": LogLevel.Info, "warning": LogLevel.Warning, "error": LogLevel.Error}
_IDENTITY = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
_TARGET_COLOUR = Color(r=1.0, g=0.2, b=0.6, a=0.9)
_FORCE_COLOUR = Color(r=0.1, g=0.6, b=1.0, a=0.8)
_POLYGON_COLOUR = Color(r=0.2, g=0.8, b=0.2, a=1.0)
_NEWTONS_PER_M = 200.0  # a force arrow's length: 1 m per 200 N


class RecordedWalking(Protocol):
    """What a recording reads of a walking motion (``wbc.locomotion.Walking`` has it): its
    commanded and measured velocity (3,) in the heading frame."""

    commanded_velocity: np.ndarray
    measured_velocity: np.ndarray


@dataclass(slots=True)
class WalkSample:
    """What a walking motion adds to a snapshot (``/walking``), velocities in the base's
    heading frame: forward, lateral [m/s] and the yaw rate [rad/s], counter-clockwise.

    ``commanded`` (3,) the motion's commanded velocity (the command after its ramps and
    envelope: what the trot follows), ``measured`` (3,) the motion's measured velocity (its
    CoM's, from the controller's state: what the trot tracks), ``measured_true`` (3,) the
    simulator's truth, the base's (``None`` on a real robot);
    ``swing_legs`` the legs out of stance in the controller's contact schedule (the gait's
    swing legs, as the snapshot's ``stance`` has them); ``loaded`` per leg (``LEGS`` order)
    whether the simulator finds it loaded (``None`` on a real robot).
    """

    commanded: np.ndarray
    measured: np.ndarray
    measured_true: np.ndarray | None = None
    swing_legs: tuple[str, ...] = ()
    loaded: tuple[bool, ...] | None = None


@dataclass(slots=True)
class Snapshot:
    """One tick as recorded: the controller's state and command, and what the robot's side
    knows (the simulator's truth and measured feet; ``None`` on a real robot).

    Arrays are copies, in the description's conventions: ``q`` (19,) Pinocchio's
    ``(x, y, z, qx, qy, qz, qw, joints)`` [m, rad], ``v`` (18,) [m/s, rad/s], ``tau`` (12,)
    [N m], ``foot_target`` (4, 3) world [m] (NaN: none), ``force_n`` (4, 3) [N] world,
    ``foot_position`` (4, 3) world [m]; ``walk`` what a walking motion adds (``None``
    while nothing walks).
    """

    t_s: float
    q: np.ndarray
    v: np.ndarray
    tau: np.ndarray
    foot_target: np.ndarray
    stance: tuple[bool, ...]
    tick_us: float
    qp_ok: bool
    status: str
    phase: str = ""
    estimate_contact: np.ndarray | None = None
    q_true: np.ndarray | None = None
    v_true: np.ndarray | None = None
    force_n: np.ndarray | None = None
    foot_position: np.ndarray | None = None
    com_margin_m: float = math.nan
    raised_leg: str = ""
    missed: bool = False
    stages_us: dict[str, float] = field(default_factory=dict)
    walk: WalkSample | None = None


def _finite(x: float) -> float | None:
    """JSON has no NaN: ``None`` (null) instead."""
    return float(x) if math.isfinite(x) else None


def _array(a: np.ndarray | None) -> list | None:
    """An array as JSON lists, to the micrometre or microradian; NaN as ``None``."""
    if a is None:
        return None
    a = np.asarray(a, dtype=float).round(6)
    finite = np.isfinite(a)
    if finite.all():
        return a.tolist()
    cells = a.astype(object)
    cells[~finite] = None
    return cells.tolist()


def _velocity(v: np.ndarray | None) -> dict[str, float] | None:
    """A heading-frame velocity (3,) as ``/walking``'s named fields."""
    if v is None:
        return None
    forward, lateral, yaw_rate = (float(x) for x in v)
    return {"forward_mps": forward, "lateral_mps": lateral, "yaw_rate_radps": yaw_rate}


def _arrow_rotation(direction: np.ndarray) -> Quaternion:
    """The rotation taking +x onto ``direction`` (a Foxglove arrow points along +x)."""
    d = direction / np.linalg.norm(direction)
    w = 1.0 + d[0]
    if w < 1e-9:  # opposite to +x: half a turn about z
        return Quaternion(x=0.0, y=0.0, z=1.0, w=0.0)
    q = np.array([0.0, -d[2], d[1], w])  # (x, y, z, w) of the half-way rotation
    q /= np.linalg.norm(q)
    return Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])


class RunRecording:
    """Snapshots of a run, queued at the tick and logged on ``channels`` off its path.

    Args:
        channels: Where the messages go.
        control_period_s: The loop's period [s].
        rate_hz: Snapshots a second of robot time (at most the control rate).
        queue_size: Snapshots queued before new ones are dropped.

    Raises:
        ConfigurationError: A rate that is not in ``(0, control rate]``.
    """

    def __init__(self, channels: RunChannels, *, control_period_s: float,
                 rate_hz: float = DEFAULT_RATE_HZ, queue_size: int = QUEUE_SNAPSHOTS):
        control_hz = 1.0 / control_period_s
        if not (math.isfinite(rate_hz) and 0.0 < rate_hz <= control_hz + 1e-9):
            raise ConfigurationError(f"recording rate_hz: expected a rate in (0, "
                                     f"{control_hz:g}] [Hz], received {rate_hz!r}")
        self.channels = channels
        #: One snapshot every this many ticks.
        self.decimation = max(1, round(control_hz / rate_hz))
        self.rate_hz = control_hz / self.decimation
        self.frames = JointFrames(channels.description.urdf_path)
        self._parents, self._children = self.frames.parents, self.frames.children
        self._origins = [Vector3(x=x, y=y, z=z) for x, y, z in self.frames.origin_xyz.tolist()]
        self._queue: deque[Snapshot] = deque()
        self._queue_size = queue_size
        self._ticks = 0
        #: Snapshots taken, logged, and dropped because the queue was full.
        self.taken = self.logged = self.dropped = 0
        #: A snapshot's messages in steps, and each step's expected time [s] (its longest
        #: recent one, decaying): what :meth:`drain` fits in the time it is given.
        self._steps = (self._log_transforms, self._log_joints, self._log_markers,
                       self._log_plots, self._log_state)
        self._expected_s = [0.0] * len(self._steps)
        self._step = 0
        self._next_description_s = -math.inf

    @property
    def port(self) -> int | None:
        """The channels' WebSocket port (``None``: no server)."""
        return self.channels.port

    def due(self) -> bool:
        """Count a tick; whether this one is to be snapshotted (every ``decimation``-th)."""
        due = self._ticks % self.decimation == 0
        self._ticks += 1
        return due

    def capture(self, snapshot: Snapshot) -> None:
        """Queue ``snapshot`` (or drop it, counted, when the queue is full)."""
        self.taken += 1
        if len(self._queue) >= self._queue_size:
            self.dropped += 1
            return
        self._queue.append(snapshot)

    def drain(self, time_left_s: float = math.inf, *,
              clock: Callable[[], float] = time.perf_counter) -> int:
        """Log queued snapshots, a step (a channel's message or two) at a time, while the
        next step is expected to fit in ``time_left_s`` [s]; returns the snapshots finished.

        Each step's expected time is its longest recent one, decaying; a step that does not
        fit decays it faster (:data:`SKIP_DECAY`), so an outlier never blocks the queue.
        """
        done = 0
        start = clock()
        steps, expected = self._steps, self._expected_s
        while self._queue:
            k = self._step
            if clock() - start + expected[k] > time_left_s:
                expected[k] *= SKIP_DECAY
                break
            t0 = clock()
            steps[k](self._queue[0])
            expected[k] = max(clock() - t0, 0.99 * expected[k])
            self._step = (k + 1) % len(steps)
            if self._step == 0:
                self._queue.popleft()
                done += 1
        self.logged += done
        return done

    def line(self, text: str, t_s: float, *, level: str = "info", name: str = "go2-wbc") -> None:
        """A log line at robot time ``t_s`` [s] (written at once: lines are few)."""
        ns = round(t_s * 1e9)
        self.channels.log.log(Log(timestamp=_stamp(ns), level=LEVELS[level], message=text,
                                  name=name), log_time=ns)

    def feedback(self, phase: str, progress: float, t_s: float) -> None:
        """An action's feedback at robot time ``t_s`` [s]."""
        self.channels.log_json("/action/feedback", {"phase": phase, "progress": progress},
                               round(t_s * 1e9))

    def close(self) -> None:
        """Log what is queued, then close the channels (the MCAP file's summary)."""
        self.drain()
        self.channels.close()

    # -- the messages --------------------------------------------------------------------

    def _log_transforms(self, s: Snapshot) -> None:
        ns = round(s.t_s * 1e9)
        ch = self.channels
        if s.t_s >= self._next_description_s:
            ch.log_description(ns)
            self._next_description_s = s.t_s + DESCRIPTION_PERIOD_S
        ch.tf.log(FrameTransforms(transforms=self._transforms(s, _stamp(ns))), log_time=ns)

    def _log_joints(self, s: Snapshot) -> None:
        ns = round(s.t_s * 1e9)
        q, v, tau = s.q[7:].tolist(), s.v[6:].tolist(), s.tau.tolist()
        self.channels.joints.log(JointStates(timestamp=_stamp(ns), joints=[
            JointState(name=name, position=q[k], velocity=v[k], effort=tau[k])
            for k, name in enumerate(JOINT_NAMES)]), log_time=ns)

    def _log_markers(self, s: Snapshot) -> None:
        ns = round(s.t_s * 1e9)
        self.channels.markers.log(self._markers(s, _stamp(ns)), log_time=ns)

    def _transforms(self, s: Snapshot, stamp: Timestamp) -> list[FrameTransform]:
        """world -> base (the estimate), world -> base_true (the truth), each joint's."""
        bases = [("base", s.q)] + ([] if s.q_true is None else [("base_true", s.q_true)])
        out = [FrameTransform(timestamp=stamp, parent_frame_id="world", child_frame_id=child,
                              translation=Vector3(x=q[0], y=q[1], z=q[2]),
                              rotation=Quaternion(x=q[3], y=q[4], z=q[5], w=q[6]))
               for child, q in ((c, q[:7].tolist()) for c, q in bases)]
        rotations = self.frames.rotations(s.q[7:]).tolist()
        for parent, child, t, r in zip(self._parents, self._children, self._origins,
                                       rotations, strict=True):
            out.append(FrameTransform(
                timestamp=stamp, parent_frame_id=parent, child_frame_id=child,
                translation=t, rotation=Quaternion(x=r[0], y=r[1], z=r[2], w=r[3])))
        return out

    def _markers(self, s: Snapshot, stamp: Timestamp) -> SceneUpdate:
        """The swing feet's targets, the measured contact forces, the support polygon."""
        spheres = [SpherePrimitive(pose=Pose(position=Vector3(x=p[0], y=p[1], z=p[2]),
                                             orientation=_IDENTITY),
                                   size=Vector3(x=0.04, y=0.04, z=0.04), color=_TARGET_COLOUR)
                   for p in s.foot_target if np.all(np.isfinite(p))]
        arrows, lines = [], []
        if s.force_n is not None and s.foot_position is not None:
            for f, p in zip(s.force_n, s.foot_position, strict=True):
                norm = float(np.linalg.norm(f))
                if norm > 1.0:
                    arrows.append(ArrowPrimitive(
                        pose=Pose(position=Vector3(x=p[0], y=p[1], z=p[2]),
                                  orientation=_arrow_rotation(f)),
                        shaft_length=norm / _NEWTONS_PER_M, shaft_diameter=0.01,
                        head_length=0.03, head_diameter=0.025, color=_FORCE_COLOUR))
            corners = [s.foot_position[k] for k in (0, 1, 3, 2) if s.stance[k]]  # around
            if len(corners) >= 3:
                lines.append(LinePrimitive(
                    type=LinePrimitiveLineType.LineLoop, thickness=0.01,
                    pose=Pose(position=Vector3(x=0.0, y=0.0, z=0.0), orientation=_IDENTITY),
                    points=[Point3(x=c[0], y=c[1], z=c[2]) for c in corners],
                    color=_POLYGON_COLOUR))
        return SceneUpdate(entities=[SceneEntity(
            timestamp=stamp, frame_id="world", id="wbc", spheres=spheres, arrows=arrows,
            lines=lines)])

    def _log_plots(self, s: Snapshot) -> None:
        """``/plot``, ``/contacts``, ``/controller/timing``, and ``/walking`` while a motion
        walks."""
        ns = round(s.t_s * 1e9)
        ch = self.channels
        foot_error = math.nan
        if s.raised_leg and s.foot_position is not None:
            k = LEGS.index(s.raised_leg)
            foot_error = float(np.linalg.norm(s.foot_position[k] - s.foot_target[k]))
        ch.log_json("/plot", {
            "base_height_m": float(s.q[2]), "base_speed_mps": float(np.linalg.norm(s.v[:3])),
            "base_height_true_m": None if s.q_true is None else float(s.q_true[2]),
            "base_speed_true_mps": (None if s.v_true is None
                                    else float(np.linalg.norm(s.v_true[:3]))),
            "foot_error_m": _finite(foot_error), "com_margin_m": _finite(s.com_margin_m)}, ns)
        ch.log_json("/contacts", {
            "legs": list(LEGS), "force_n": _array(s.force_n),
            "normal_force_n": None if s.force_n is None else _array(s.force_n[:, 2]),
            "estimate_contact": _array(s.estimate_contact), "stance": list(s.stance)}, ns)
        ch.log_json("/controller/timing", {
            "tick_us": _finite(s.tick_us), "qp_ok": s.qp_ok, "status": s.status,
            "missed": s.missed, "stages_us": s.stages_us, "dropped": self.dropped}, ns)
        if s.walk is not None:
            w = s.walk
            ch.log_walking({
                "commanded": _velocity(w.commanded), "measured": _velocity(w.measured),
                "measured_true": _velocity(w.measured_true), "swing_legs": list(w.swing_legs),
                "legs": list(LEGS), "loaded": None if w.loaded is None else list(w.loaded)},
                ns)

    def _log_state(self, s: Snapshot) -> None:
        """``/wbc/state``: the arrays a replay reads back."""
        ns = round(s.t_s * 1e9)
        self.channels.log_json("/wbc/state", {
            "t_s": s.t_s, "q": _array(s.q), "v": _array(s.v), "tau": _array(s.tau),
            "q_true": _array(s.q_true), "v_true": _array(s.v_true),
            "foot_target": _array(s.foot_target), "foot_position": _array(s.foot_position),
            "force_n": _array(s.force_n), "com_margin_m": _finite(s.com_margin_m),
            "phase": s.phase, "raised_leg": s.raised_leg, "tick_us": _finite(s.tick_us),
            "qp_ok": s.qp_ok,
            "commanded_velocity": None if s.walk is None else _array(s.walk.commanded)}, ns)


def _stamp(ns: int) -> Timestamp:
    return Timestamp(sec=ns // 1_000_000_000, nsec=ns % 1_000_000_000)
