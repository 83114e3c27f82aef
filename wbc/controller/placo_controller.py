"""The same balance tasks solved by PlaCo's DynamicsSolver, behind the BalanceController."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import pinocchio as pin
import placo

from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.controller.controller_config import ControllerConfig, config_with_overrides
from wbc.controller.foot_reach import FootReach
from wbc.controller.motor_command_shaper import MotorCommandShaper, joint_types
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, as_vector, check_name
from wbc.model.description import FOOT_FRAMES, JOINT_NAMES, LEGS, Go2Description

#: Smallest normal-force ratio the force-weight ramp divides by (caps the weight at 1e6x).
MIN_FORCE_RATIO = 1e-3


class PlacoController:
    """Whole-body balance of the GO2 with ``placo.DynamicsSolver`` (one QP per tick).

    The tasks and contacts mirror :class:`wbc.WholeBodyController`, with the same
    :class:`ControllerConfig` gains and weights and the same :class:`ContactSchedule`;
    PlaCo builds and solves the QP (its own eiquadprog, variables ``[qdd (18), one force
    (3) per active contact]``), so the configured QP backend is ignored. PlaCo's soft terms
    cost ``weight/2 ||A x - b||^2`` like ours, so weights carry over one to one:

    - CoM: ``add_com_task``, soft, ``com_weight``, ``kp = com_kp``, critical damping. Base
      orientation: ``add_orientation_task("base")``, soft, ``base_orientation_weight``,
      ``base_orientation_kp``; the target keeps the reset yaw with zero roll and pitch.
    - Posture: one ``add_joints_task`` per joint (PlaCo's has a single weight, ours per-joint
      multipliers), soft, ``posture_weight`` times the multiplier, ``posture_kp``. Twelve
      tasks instead of one cost PlaCo about 20 us a tick.
    - One position task per foot. A stance foot's is *hard*, ``kp = 0``, ``kd =
      contact_damping``, with a unilateral point contact (``mu = friction_coefficient``,
      ``weight_forces = force_weight``); a swing foot's contact is off and its task soft,
      ``foot_weight`` (or :meth:`set_foot_weight`'s), ``foot_kp``.
    - Torque limits: ``torque_limit_fraction`` of the URDF efforts (``set_torque_limit``).
      Joint limits: PlaCo's own with ``dt = joint_limit_horizon_s`` (velocity rows equal to
      the reference's; position rows by PlaCo's braking model, ``qdd_safe = 1 rad/s^2``).
      PlaCo's torque cost (``1e-3``) is set to zero: the reference has no such term.

    What is *not* equivalent:

    - No upper bound on a contact force exists in PlaCo 0.10.2: the schedule's bound (set or
      ramped) raises the contact's force weight instead, ``force_weight / max(r, 1e-3)^2``
      with ``r = bound / full bound``: the load moves off the foot smoothly, but by a
      penalty, not a bound (the reference keeps the natural load until the bound reaches
      it); the rest vanishes when the schedule's ``set_swing`` deactivates the contact.
    - No minimum normal force (PlaCo only has ``f_z >= 0``), no support-polygon barrier, no
      acceleration/force rate terms, no rolling-foot model (the contact point is the foot
      sphere's centre).
    - ``timings`` has ``model`` (``update_kinematics``), ``solve`` (PlaCo's task update,
      assembly and solve) and ``total``. :meth:`solution_violations` checks the last
      solution on PlaCo's hard rows, off the hot path.

    Example:
        >>> controller = PlacoController()
        >>> controller.reset(q)
        >>> out = controller.step(q, v)        # tau = PlaCo's result.tau[6:]
    """

    def __init__(self, config: ControllerConfig | None = None, *,
                 description: Go2Description | None = None, **overrides: Any):
        """Args:
            config: Gains, weights and limits (see :class:`ControllerConfig`).
            description: The robot files (found automatically by default).
            **overrides: Parts of :class:`ControllerConfig` to change (a part, or a mapping of
                some of its fields), e.g. ``gains={"com_kp": 100.0}``.
        """
        self.config = cfg = config_with_overrides(config, overrides)
        self.description = description or Go2Description.default()
        # PlaCo resolves the URDF's package:// mesh URIs even when it ignores collisions.
        self.description.set_ros_package_path()
        self.robot = robot = placo.RobotWrapper(str(self.description.urdf_path),
                                                placo.Flags.ignore_collisions)
        if list(robot.joint_names()) != list(JOINT_NAMES):
            raise ConfigurationError(
                f"PlaCo joint order {list(robot.joint_names())} differs from {JOINT_NAMES}")
        self._nv = robot.model.nv
        self._nj = self._nv - 6
        self.tau_max = cfg.limits.torque_limit_fraction * self.description.effort_limit

        self.solver = solver = placo.DynamicsSolver(robot)
        solver.mask_fbase(False)
        # dt only enters PlaCo's limit rows here (no integration). With the 1 ms tick they
        # chattered (the joint-limit row ``qd + dt qdd <= sqrt(2 d qdd_safe)`` is a 1/dt gain);
        # our own limit horizon makes the velocity rows identical to the reference's.
        solver.dt = cfg.limits.joint_limit_horizon_s
        solver.torque_cost = 0.0
        solver.enable_torque_limits(True)
        for name, limit in zip(JOINT_NAMES, self.tau_max):
            solver.set_torque_limit(name, float(limit))
        solver.enable_joint_limits(True)
        solver.enable_velocity_limits(True)

        robot.update_kinematics()
        self.com_task = solver.add_com_task(robot.com_world())
        self.com_task.configure("com", "soft", cfg.weights.com_weight)
        self.base_task = solver.add_orientation_task("base", np.eye(3))
        self.base_task.configure("base_orientation", "soft", cfg.weights.base_orientation_weight)
        # One joints task per joint: PlaCo's joints task has one weight, ours per-joint ones.
        self.posture_tasks = [solver.add_joints_task() for _ in JOINT_NAMES]
        gains = cfg.gains
        for task, kp in ((self.com_task, gains.com_kp), (self.base_task, gains.base_orientation_kp),
                         *((t, gains.posture_kp) for t in self.posture_tasks)):
            task.kp, task.kd = kp, 2.0 * math.sqrt(kp)
        self._posture = np.zeros(self._nj)
        self.set_posture_weights(np.ones(self._nj))
        self.foot_tasks = {}
        self.contacts = {}
        for leg in LEGS:
            task = solver.add_position_task(FOOT_FRAMES[leg], np.zeros(3))
            contact = solver.add_point_contact(task)
            contact.unilateral = True
            contact.mu = cfg.contacts.friction_coefficient
            self.foot_tasks[leg], self.contacts[leg] = task, contact
        self._q: np.ndarray | None = None
        period_s = cfg.solver.control_period_s
        self.motor = MotorCommandShaper(cfg.shaping, control_period_s=period_s,
                                        tau_max=self.tau_max,
                                        effort_limit=self.description.effort_limit,
                                        joint_types=joint_types(JOINT_NAMES))
        self._foot_weight = dict.fromkeys(LEGS, cfg.weights.foot_weight)
        self._leg_joints = {leg: self.description.leg_joint_indices(leg) for leg in LEGS}
        self.reach = FootReach(self.description, LEGS)
        #: Which feet stand, their force bounds and the ramps (PlaCo's contacts follow it).
        self.schedule = ContactSchedule(LEGS, cfg.contacts,
                                        control_period_s=period_s,
                                        listener=self._configure_foot)
        for leg in LEGS:
            self._configure_foot(leg)
        self._tau_good = np.zeros(self._nj)
        self._last: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.ticks = self.failures = 0

    # ------------------------------------------------------------------ references

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: every target from it (the base level at its yaw), every
        foot in stance."""
        q = as_vector("q", q, self.robot.model.nq)
        v = np.zeros(self._nv) if v is None else as_vector("v", v, self._nv)
        self._update_model(q, v)
        robot = self.robot
        self.set_com_target(robot.com_world())
        yaw = pin.rpy.matrixToRpy(robot.get_T_world_frame("base")[:3, :3])[2]
        self.base_task.R_world_frame = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
        self.set_posture_target(q[7:])
        self.set_posture_weights(np.ones(self._nj))
        for leg in LEGS:
            self.set_foot_target(leg, self.foot_position(leg))
            self._foot_weight[leg] = self.config.weights.foot_weight
        self.schedule.reset()  # every foot configured again
        result = self.solver.solve(False)
        self._tau_good = (np.array(result.tau[6:]) if result.success
                          else robot.static_gravity_compensation_torques("base")[6:].copy())
        self.motor.reference.reset(q[7:], v[6:])

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass target [m], velocity [m/s] and feed-forward acceleration [m/s^2]."""
        self.com_task.target_world = as_vector("com target", position, 3)
        self.com_task.dtarget_world = _vector_or_zero("com velocity", velocity)
        self.com_task.ddtarget_world = _vector_or_zero("com acceleration", acceleration)

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target [rad], description order (a copy)."""
        return self._posture.copy()

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture target [rad], velocity [rad/s] and feed-forward [rad/s^2]."""
        n = self._nj
        target = as_vector("posture target", joint_positions, n)
        rate = np.zeros(n) if velocity is None else as_vector("posture velocity", velocity, n)
        accel = (np.zeros(n) if acceleration is None
                 else as_vector("posture acceleration", acceleration, n))
        for task, name, *values in zip(self.posture_tasks, JOINT_NAMES, target, rate, accel):
            task.set_joint(name, *map(float, values))
        self._posture = target

    def set_posture_weights(self, weights: np.ndarray) -> None:
        """Per-joint multipliers of the posture weight; ones restore the default."""
        weights = as_vector("posture weights", weights, self._nj)
        if np.any(weights < 0.0):
            raise ConfigurationError(
                f"posture weights: expected values >= 0, received {weights.tolist()}")
        for task, name, weight in zip(self.posture_tasks, JOINT_NAMES, weights):
            task.configure(f"posture {name}", "soft",
                           self.config.weights.posture_weight * float(weight))

    def set_foot_weight(self, leg: str, weight: float | None = None) -> None:
        """Weight of a swing foot's position task (0 hands the leg to the posture task;
        ``None`` restores the configured ``foot_weight``)."""
        check_name("leg", leg, LEGS)
        weight = self.config.weights.foot_weight if weight is None else weight
        self._foot_weight[leg] = as_float(f"{leg} foot weight", weight, low=0.0)
        self._configure_foot(leg)

    @property
    def com_target(self) -> np.ndarray:
        """The current centre-of-mass target [m] (a copy)."""
        return np.array(self.com_task.target_world, dtype=float).reshape(3)

    def com_position(self) -> np.ndarray:
        """Centre of mass [m] at the last state."""
        return np.array(self.robot.com_world(), dtype=float).reshape(3)

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity [m/s] at the last state."""
        return np.asarray(self.robot.com_jacobian() @ self.robot.state.qd, float).reshape(3)

    def foot_position(self, leg: str) -> np.ndarray:
        """World position [m] of a foot frame (sphere centre) at the last state."""
        check_name("leg", leg, LEGS)
        return self.robot.get_T_world_frame(FOOT_FRAMES[leg])[:3, 3].copy()

    def foot_positions(self) -> np.ndarray:
        """World positions (legs, 3) [m] of the foot frames at the last state, legs' order."""
        return np.array([self.robot.get_T_world_frame(FOOT_FRAMES[leg])[:3, 3] for leg in LEGS])

    def foot_target(self, leg: str) -> np.ndarray | None:
        """A foot's world position target [m] (a copy): where it is held while it swings."""
        check_name("leg", leg, LEGS)
        return np.array(self.foot_tasks[leg].target_world, dtype=float).reshape(3)

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """World target [m], velocity [m/s] and feed-forward acceleration of a foot, tracked
        while it swings; beyond the leg's reach it is refused (``ReachabilityError``, the
        target unchanged) or, with ``clamp_to_reach``, moved onto it."""
        position = self.reach.reachable_target(leg, position, self._base_placement(),
                                               clamp=clamp_to_reach)
        task = self.foot_tasks[leg]
        task.target_world = position
        task.dtarget_world = _vector_or_zero(f"{leg}_foot velocity", velocity)
        task.ddtarget_world = _vector_or_zero(f"{leg}_foot acceleration", acceleration)

    def normal_force(self, leg: str) -> float:
        """The normal force [N] the last solved tick gave a foot (0 before any)."""
        check_name("leg", leg, LEGS)
        return 0.0 if self._last is None else float(self._last[2][LEGS.index(leg), 2])

    def _base_placement(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self._q is None:
            return None
        T_world_base = self.robot.get_T_world_frame("base")
        return T_world_base[:3, :3], T_world_base[:3, 3]

    @property
    def control_period_s(self) -> float:
        """The period [s] the controller runs at (its motor command integrates over it)."""
        return self.config.solver.control_period_s

    def shoulder_position(self, leg: str) -> np.ndarray:
        """World position [m] of a leg's shoulder (fixed to the base) at the last state."""
        return self.reach.shoulder_position(leg, self._base_placement())

    @property
    def stance_legs(self) -> list[str]:
        """Legs in stance (the schedule's)."""
        return self.schedule.stance_legs

    def support_legs(self) -> list[str]:
        """Fully loaded stance legs: the support polygon's corners (the schedule's)."""
        return self.schedule.support_legs()

    def normal_force_bounds(self, out: np.ndarray) -> np.ndarray:
        """Each foot's normal-force bound [N] into ``out``, 0 in swing (the schedule's)."""
        return self.schedule.normal_force_bounds(out)

    def _configure_foot(self, leg: str) -> None:
        """The schedule's listener. Stance: hard zero-acceleration task with a contact, its
        force weighted by the bound; swing: soft tracking task."""
        cfg, task, contact = self.config, self.foot_tasks[leg], self.contacts[leg]
        stance = self.schedule.is_stance(leg)
        self.motor.set_stance(self._leg_joints[leg], stance)
        if stance:
            task.configure(f"{leg}_contact", "hard", 1.0)
            task.kp, task.kd = 0.0, cfg.gains.contact_damping
            ratio = max(self.schedule.max_normal_force(leg) / cfg.contacts.max_normal_force_n,
                        MIN_FORCE_RATIO)
            contact.weight_forces = cfg.weights.force_weight / (ratio * ratio)
            contact.active = True
        else:
            task.configure(f"{leg}_foot", "soft", self._foot_weight[leg])
            task.kp, task.kd = cfg.gains.foot_kp, 2.0 * math.sqrt(cfg.gains.foot_kp)
            contact.active = False

    # ------------------------------------------------------------------ the tick

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick: PlaCo's kinematics update and QP solve (no integration). Never
        raises on bad numbers in the state or a failed solve: it returns the safe fallback
        command (joint damping around the last good torques), status ``FALLBACK``."""
        t0 = time.perf_counter()
        self.ticks += 1
        self.schedule.advance()  # a ramping bound re-weighs its contact
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        nq, nv = self.robot.model.nq, self._nv
        if q.shape != (nq,) or v.shape != (nv,):
            return self._fallback(v, f"state: expected q {(nq,)} and v {(nv,)}, "
                                     f"received {q.shape} and {v.shape}", t0)
        if not (np.isfinite(q).all() and np.isfinite(v).all()):
            bad = [f"q[{i}]" for i in np.flatnonzero(~np.isfinite(q))]
            bad += [f"v[{i}]" for i in np.flatnonzero(~np.isfinite(v))]
            return self._fallback(v, f"state: non-finite values at {', '.join(bad)}", t0)
        self._update_model(q, v)
        t1 = time.perf_counter()
        try:
            result = self.solver.solve(False)
        except Exception as err:  # noqa: BLE001 - a solver error must not escape the tick
            return self._fallback(v, f"PlaCo solve raised {type(err).__name__}: {err}", t0)
        t2 = time.perf_counter()
        if not result.success:
            return self._fallback(v, "PlaCo QP failed (infeasible or not solved)", t0)
        tau_full = np.array(result.tau, dtype=float)
        qdd = np.array(result.qdd, dtype=float)
        if not (np.isfinite(tau_full).all() and np.isfinite(qdd).all()):
            return self._fallback(v, "PlaCo returned non-finite torques or accelerations", t0)
        forces = np.zeros((len(LEGS), 3))
        for i, leg in enumerate(LEGS):
            if self.schedule.is_stance(leg):
                forces[i] = np.asarray(self.contacts[leg].wrench, dtype=float).reshape(3)
        tau_qp = tau_full[6:]
        self._tau_good = tau_qp
        self._last = (tau_full, qdd, forces)
        command = self.motor.shape(q[7:], v[6:], qdd[6:], tau_qp)
        task_errors = self._task_errors(q)
        t3 = time.perf_counter()
        return ControlOutput(
            **command, qdd=qdd, forces=forces, status=ControlStatus.OK, task_errors=task_errors,
            timings={"model": t1 - t0, "solve": t2 - t1, "total": t3 - t0},
        )

    def _update_model(self, q: np.ndarray, v: np.ndarray) -> None:
        self.robot.state.q, self.robot.state.qd = q, v
        self.robot.update_kinematics()
        self._q = q

    def solution_violations(self) -> tuple[float, float]:
        """Largest equality (floating-base torque, stance feet's accelerations) and
        inequality (torque limits, unilateral and friction rows) violation of the last
        solution on PlaCo's hard rows; ``(nan, nan)`` after a fallback. Off the hot path:
        call it right after :meth:`step`, before the contacts change."""
        if self._last is None:
            return math.nan, math.nan
        tau_full, qdd, forces = self._last
        eq = float(np.abs(tau_full[:6]).max())
        mu = self.config.contacts.friction_coefficient
        ineq = float(max((np.abs(tau_full[6:]) - self.tau_max).max(), 0.0))
        for i, leg in enumerate(LEGS):
            if not self.schedule.is_stance(leg):
                continue
            task = self.foot_tasks[leg]
            residual = np.asarray(task.A) @ qdd - np.asarray(task.b).reshape(-1)
            eq = max(eq, float(np.abs(residual).max()))
            fx, fy, fz = forces[i]
            ineq = max(ineq, -fz, abs(fx) - mu * fz, abs(fy) - mu * fz)
        return eq, ineq

    def _task_errors(self, q: np.ndarray) -> dict[str, float]:
        errors = {"com": float(np.linalg.norm(self.com_task.error)),
                  "base_orientation": float(np.linalg.norm(self.base_task.error)),
                  "posture": float(np.linalg.norm(self._posture - q[7:]))}
        for leg in LEGS:
            if not self.schedule.is_stance(leg):
                errors[f"{leg}_foot"] = float(np.linalg.norm(self.foot_tasks[leg].error))
        return errors

    def safe_command(self, v: np.ndarray, message: str) -> ControlOutput:
        """The safe fallback command for velocity ``v``, with status FALLBACK and ``message``."""
        return self._fallback(v, message, time.perf_counter())

    def _fallback(self, v: np.ndarray, message: str, t0: float) -> ControlOutput:
        """Safe command: the last good torques with joint damping, inside the limits."""
        self.failures += 1
        self._last = None
        self.motor.reference.release()
        return ControlOutput.damped_hold(
            self._tau_good, v, damping=self.config.shaping.fallback_damping, tau_max=self.tau_max,
            message=message, elapsed_s=time.perf_counter() - t0, contacts=len(LEGS),
            q_joints=None if self._q is None else self._q[7:])


def _vector_or_zero(name: str, value: np.ndarray | None) -> np.ndarray:
    return np.zeros(3) if value is None else as_vector(name, value, 3)
