"""Moving the whole body between the standing and the lying pose on four feet."""

from __future__ import annotations

import enum
from functools import lru_cache

import numpy as np
import pinocchio as pin

from wbc.controller.balance_controller import BalanceController
from wbc.core.min_jerk import min_jerk_segment
from wbc.core.validation import as_float, check_name
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS, Go2Description
from wbc.motions.leg_lift import LegLift, LiftPhase


class TransitionPhase(enum.StrEnum):
    """Phases of a posture transition."""

    PLACING_FOOT = "placing_foot"  # a foot left in the air is put down first
    MOVING = "moving"              # centre of mass and joints move to the pose
    DONE = "done"


@lru_cache(maxsize=8)
def _pose_geometry(description: Go2Description, pose: str
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A pose's configuration (19,), its centre of mass relative to its feet (3,) and each
    foot relative to its shoulder (4, 2) [m], computed once: a behaviour starts a
    transition inside a control tick, where a forward kinematics pass and a new model
    would cost about a millisecond."""
    q_pose = description.pose(pose)
    model = description.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q_pose)
    feet = np.array([data.oMf[model.getFrameId(FOOT_FRAMES[leg])].translation for leg in LEGS])
    com = pin.centerOfMass(model, data, q_pose)
    com_offset = np.array([*(com[:2] - feet[:, :2].mean(axis=0)),
                           com[2] - (feet[:, 2].min() - FOOT_RADIUS_M)])
    shoulders = np.array([data.oMi[model.getJointId(f"{leg}_thigh_joint")].translation[:2]
                          for leg in LEGS])
    return q_pose, com_offset, feet[:, :2] - shoulders


class PostureTransition:
    """Brings the robot to a named pose (``standing`` or ``lying``) with its feet where they are.

    The centre-of-mass target moves, with a minimum-jerk profile, to the pose's height and
    to the pose's place relative to the feet; the posture target moves to the pose's joint
    angles. A foot in the air is first put down under its shoulder.
    """

    def __init__(self, controller: BalanceController, pose: str = "standing", *,
                 duration_s: float = 2.0, description: Go2Description | None = None):
        """Args:
            controller: The whole-body controller.
            pose: ``"standing"`` or ``"lying"``.
            duration_s: Duration of the motion [s] (after any foot placement).
            description: The robot files (the controller's by default).
        """
        self.controller = controller
        self.description = description or controller.description
        self.pose = check_name("pose", pose, self.description.poses)
        self.duration_s = as_float("duration_s", duration_s, low=0.2, high=30.0)
        self.phase: TransitionPhase | None = None
        q_pose, com_offset, under_shoulder = _pose_geometry(self.description, pose)
        self._q_pose = q_pose.copy()
        #: The pose's centre of mass relative to its feet: xy from their centroid, z above ground.
        self.com_offset = com_offset.copy()
        #: Where a foot stands relative to its shoulder in the pose (xy).
        self.foot_under_shoulder = {leg: under_shoulder[i].copy() for i, leg in enumerate(LEGS)}
        self._placing: LegLift | None = None
        self.progress = 0.0

    def _com_goal(self) -> np.ndarray:
        feet = np.array(self.controller.foot_positions())
        ground = feet[:, 2].min() - FOOT_RADIUS_M
        xy = feet[:, :2].mean(axis=0) + self.com_offset[:2]
        return np.array([xy[0], xy[1], ground + self.com_offset[2]])

    def start(self, now_s: float) -> None:
        """Plan from the controller's last state and begin."""
        ctrl = self.controller
        swing = [leg for leg in LEGS if not ctrl.schedule.is_stance(leg)]
        if swing:
            leg = swing[0]
            ground = ctrl.shoulder_position(leg)[:2] + self.foot_under_shoulder[leg]
            point = np.array([ground[0], ground[1], FOOT_RADIUS_M])
            home = ctrl.com_target
            self._placing = LegLift.put_down(ctrl, leg, point, home, now_s)
            self.phase = TransitionPhase.PLACING_FOOT
        else:
            self._begin_moving(now_s)

    def _begin_moving(self, now_s: float) -> None:
        ctrl = self.controller
        self._com_from, self._com_to = ctrl.com_target, self._com_goal()
        self._joints_from = ctrl.posture_target
        self._t0 = now_s
        self.phase = TransitionPhase.MOVING

    def advance(self, now_s: float) -> TransitionPhase:
        """Set the controller's references for time ``now_s`` [s]; returns the phase."""
        if self.phase is TransitionPhase.PLACING_FOOT:
            if self._placing.advance(now_s) is LiftPhase.DONE:
                self._begin_moving(now_s)
            self.progress = max(self.progress, 0.3 * self._placing.progress)
        if self.phase is TransitionPhase.MOVING:
            elapsed = now_s - self._t0
            p, v, a = min_jerk_segment(self._com_from, self._com_to, elapsed, self.duration_s)
            self.controller.set_com_target(p, v, a)
            joints = min_jerk_segment(self._joints_from, self._q_pose[7:], elapsed,
                                      self.duration_s)[0]
            self.controller.set_posture_target(joints)
            start = 0.3 if self._placing is not None else 0.0
            self.progress = max(self.progress,
                                start + (1.0 - start) * min(elapsed / self.duration_s, 1.0))
            if elapsed >= self.duration_s:
                self.phase = TransitionPhase.DONE
        return self.phase

    def stop(self) -> None:
        """Freeze the references where they are (a smooth stop for a cancel)."""
        ctrl = self.controller
        if self.phase is TransitionPhase.MOVING:
            ctrl.set_com_target(ctrl.com_target)
        if self.phase is TransitionPhase.PLACING_FOOT:
            return  # finishing the placement is the safe way out; the caller keeps updating
        self.phase = TransitionPhase.DONE
