"""The whole-body inverse-dynamics QP controller of the GO2."""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

import numpy as np
import pinocchio as pin

from tasks import BaseOrientationTask, ComTask, ContactTask, FramePositionTask, PostureTask
from wbc import qp_kernel
from wbc.backends import INFINITY, QpProblem, QpResult, make_backend
from wbc.contact_modes import ContactModes
from wbc.control_output import ControlOutput, ControlStatus
from wbc.controller_config import ControllerConfig
from wbc.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS, Go2Description
from wbc.errors import ConfigurationError
from wbc.motor_command_shaper import MotorCommandShaper
from wbc.support_polygon import SupportPolygon
from wbc.validation import as_vector, check_name

_NV, _NJ, _NC = 18, 12, 4
_F0 = _NV                  # first force variable
_S = _NV + 3 * _NC         # the support-polygon slack variable
_N = _S + 1                # number of variables
_DYN = slice(0, 6)         # floating-base equations of motion
_CON = slice(6, 18)        # stance feet do not accelerate
_TAU = slice(18, 30)       # torque limits
_FRIC = slice(30, 46)      # friction pyramids
_SUP = slice(46, 50)       # centre of mass inside the support polygon (soft)
_M = 50
_LEG_INDEX = {leg: i for i, leg in enumerate(LEGS)}
_ALL_LEGS = tuple(LEGS)
#: Per-tick decay of the orientation integral while not on four loaded feet (0.1 s).
_INTEGRAL_FADE = 0.99
_GROUPS = (("dynamics", _DYN), ("stance contacts", _CON), ("torque limits", _TAU),
           ("friction", _FRIC), ("support polygon", _SUP))


class WholeBodyController(ContactModes):
    """Force-level whole-body control of the GO2 by one QP per tick.

    Decision variables ``x = [qdd (18), f (4 x 3), s]``: generalized accelerations, world
    contact forces of the four feet, and one slack of the support-polygon constraint.
    Torques are recovered from the equations of motion, ``tau = M_a qdd + h_a - J_a^T f``,
    so the QP stays at 31 variables whatever the contacts. Minimises the weighted task
    errors (centre of mass, base orientation, swing feet, posture), a torque-rate term and
    small regularisations, subject to:

    - the floating-base rows of the equations of motion ``M_u qdd + h_u = J_u^T f``;
    - stance feet fixed: ``J_c qdd + Jdot_c v = -kd v_c``;
    - friction pyramids, with minimum and maximum normal force per foot (a swing foot's
      force is zero; a foot being unloaded has its maximum ramped down by the caller);
    - torque limits (a fraction of the URDF's), joint position and velocity limits as
      acceleration bounds;
    - the centre of mass inside the support polygon with a margin, as a soft barrier.

    Example:
        >>> controller = WholeBodyController()            # GO2, DAQP, default gains
        >>> controller.reset(q)                           # hold the current pose
        >>> out = controller.step(q, v)                   # 1 kHz
        >>> out.tau, out.status, out.timings["total"]
    """

    def __init__(self, config: ControllerConfig | None = None, *,
                 description: Go2Description | None = None, **overrides: Any):
        """Args:
            config: All parameters (see :class:`ControllerConfig`); defaults when ``None``.
            description: The robot files (found automatically by default).
            **overrides: Fields of :class:`ControllerConfig` to change, e.g. ``backend="osqp"``.
        """
        base = config or ControllerConfig()
        unknown = sorted(set(overrides) - set(ControllerConfig.__dataclass_fields__))
        if unknown:
            valid = ", ".join(ControllerConfig.__dataclass_fields__)
            raise ConfigurationError(f"unknown parameter(s) {unknown}; valid parameters: {valid}")
        self.config = replace(base, **overrides)
        cfg = self.config
        self.description = description or Go2Description()
        self.model = self.description.build_model()
        self.data = self.model.createData()
        self.backend = make_backend(cfg.backend)
        self.tau_max = cfg.torque_limit_fraction * self.description.effort_limit

        self.com_task = ComTask(kp=cfg.com_kp, weight=cfg.com_weight)
        self.base_task = BaseOrientationTask(kp=cfg.base_orientation_kp,
                                             weight=cfg.base_orientation_weight)
        self.posture_task = PostureTask(kp=cfg.posture_kp, weight=cfg.posture_weight)
        self.foot_tasks = {leg: FramePositionTask(self.model, FOOT_FRAMES[leg], kp=cfg.foot_kp,
                                                  weight=cfg.foot_weight) for leg in LEGS}
        self.contact_task = ContactTask(self.model, [FOOT_FRAMES[leg] for leg in LEGS],
                                        kd=cfg.contact_damping, radius_m=FOOT_RADIUS_M)
        self.support = SupportPolygon(margin_m=cfg.support_margin_m)

        self._q_low = self.description.position_lower
        self._q_high = self.description.position_upper
        self._v_max = self.description.velocity_limit
        self.motor = MotorCommandShaper(cfg, tau_max=self.tau_max,
                                        effort_limit=self.description.effort_limit)
        self._init_contact_modes()
        self._build_problem()
        self._contacts_changed()
        self._tau_prev = np.zeros(_NJ)
        self._tau_good = np.zeros(_NJ)
        self._q: np.ndarray | None = None
        self.ticks = 0
        self.failures = 0
        #: The last solved QP's solution ``[qdd (18), forces (12), slack]`` (NaN before any).
        self.last_solution = np.full(_N, np.nan)

    # ------------------------------------------------------------------ references

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: every target is set from it, all four feet in stance.

        The base orientation target keeps the current yaw with zero roll and pitch.
        """
        q = as_vector("q", q, self.model.nq)
        v = np.zeros(_NV) if v is None else as_vector("v", v, _NV)
        self._update_model(q, v)
        self.com_task.set_target(self.data.com[0])
        yaw = pin.rpy.matrixToRpy(self.data.oMi[1].rotation)[2]
        self.base_task.set_rpy(0.0, 0.0, yaw)
        self.posture_task.set_target(q[7:])
        for leg, task in self.foot_tasks.items():
            task.set_target(self.data.oMf[task.frame_id].translation)
        for leg in LEGS:
            self._stance[leg] = True
            self._max_force[leg] = self.config.max_normal_force_n
            self.foot_tasks[leg].set_weight(self.config.foot_weight)
        self.posture_task.set_joint_weights(np.ones(_NJ))
        self._base_integral[:] = 0.0
        self._contacts_changed()
        gravity = pin.computeGeneralizedGravity(self.model, self.data, q)
        self._tau_prev = self._static_torques(q, gravity)
        self._tau_good = self._tau_prev.copy()
        self.motor.reference.reset(q[7:], v[6:])
        self.backend.setup(self.problem)

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass target [m], velocity [m/s] and feed-forward acceleration [m/s^2]."""
        self.com_task.set_target(position, velocity)
        self.com_task.set_feedforward(np.zeros(3) if acceleration is None else acceleration)

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target [rad] (12,), description order (a copy)."""
        return self.posture_task._require_target().copy()

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture target [rad], velocity [rad/s] and feed-forward [rad/s^2] (12,)."""
        self.posture_task.set_target(joint_positions, velocity)
        self.posture_task.set_feedforward(np.zeros(_NJ) if acceleration is None else acceleration)

    def set_posture_weights(self, weights: np.ndarray) -> None:
        """Per-joint multipliers (12,) of the posture weight; ones restore the default."""
        self.posture_task.set_joint_weights(weights)

    def set_foot_weight(self, leg: str, weight: float) -> None:
        """Weight of a swing foot's position task (0 hands the leg to the posture task)."""
        check_name("leg", leg, LEGS)
        self.foot_tasks[leg].set_weight(weight)

    @property
    def com_target(self) -> np.ndarray:
        """The current centre-of-mass target [m] (a copy)."""
        return self.com_task._require_target().copy()

    def com_position(self) -> np.ndarray:
        """Centre of mass [m] at the last state."""
        return self.data.com[0].copy()

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity [m/s] at the last state."""
        return self.data.vcom[0].copy()

    def foot_position(self, leg: str) -> np.ndarray:
        """World position [m] of a foot frame (sphere centre) at the last state."""
        check_name("leg", leg, LEGS)
        return self._foot_pos[_LEG_INDEX[leg]].copy()

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """World target [m], velocity [m/s] and feed-forward acceleration of a foot.

        Tracked while the leg swings. With ``clamp_to_reach`` a target beyond the leg's
        reach is moved onto it (for motion generators that must never stop) instead of
        raising.

        Raises:
            ReachabilityError: The target is farther than :data:`LEG_REACH_M` from the leg's
                shoulder at the last state; the target is left unchanged.
        """
        position = self._reachable_target(leg, position, clamp_to_reach)
        self.foot_tasks[leg].set_target(position, velocity)
        self.foot_tasks[leg].set_feedforward(np.zeros(3) if acceleration is None else acceleration)

    def _contact_mode_changed(self, leg: str) -> None:
        self._contacts_changed()

    def _base_placement(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self._q is None:
            return None
        base = self.data.oMi[1]
        return base.rotation, base.translation

    def normal_force(self, leg: str) -> float:
        """The normal force [N] the last solved tick gave a foot (0 before any)."""
        check_name("leg", leg, LEGS)
        value = self.last_solution[_F0 + 3 * _LEG_INDEX[leg] + 2]
        return float(value) if math.isfinite(value) else 0.0

    # ------------------------------------------------------------------ the tick

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick: model update, tasks and QP assembly, solve.

        Never raises on bad numbers in the state or a failed solve: it returns the safe
        fallback command (joint damping around the last good torques) with status
        ``FALLBACK`` and a message, and stays usable for the next tick.
        """
        t0 = time.perf_counter()
        self.ticks += 1
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        if q.shape != (self.model.nq,) or v.shape != (_NV,):
            return self._fallback(v, f"state: expected q {(self.model.nq,)} and v {(_NV,)}, "
                                     f"received {q.shape} and {v.shape}", t0)
        if not (math.isfinite(q.sum()) and math.isfinite(v.sum())):
            bad = [f"q[{i}]" for i in np.flatnonzero(~np.isfinite(q))]
            bad += [f"v[{i}]" for i in np.flatnonzero(~np.isfinite(v))]
            return self._fallback(v, f"state: non-finite values at {', '.join(bad)}", t0)
        self._update_model(q, v)
        t1 = time.perf_counter()
        self._assemble(q, v)
        t2 = time.perf_counter()
        result = self.backend.solve(self.problem)
        t3 = time.perf_counter()
        status, message, group = ControlStatus.OK, "", ""
        if not result.found:
            self.failures += 1
            message = f"QP failed: {result.reason}"
            # The solver's workspace may hold a bad state after a failure.
            self.backend.setup(self.problem)
            retry = self._fresh_solve(self.problem)
            if retry.found:  # a solver failure, not an infeasible problem
                result, status = retry, ControlStatus.RESOLVED
                message += "; the problem is feasible: commanded a fresh DAQP solution"
            else:
                group, relaxed = self.diagnose()
                if group:
                    message += f"; infeasible constraint group: {group}"
                if relaxed is None:
                    return self._fallback(v, message, t0, group=group)
                result, status = relaxed, ControlStatus.RELAXED
                message += "; commanded the solution with that group relaxed"
        x = result.x
        tau_qp = self.problem.A[_TAU, :_S] @ x[:_S] + self.data.nle[6:]
        if status is not ControlStatus.OK:
            np.clip(tau_qp, -self.tau_max, self.tau_max, out=tau_qp)
        self._x_prev[:] = x[:_S]
        self.last_solution = x
        self._tau_prev = tau_qp
        self._tau_good = tau_qp
        command = self.motor.shape(q[7:], v[6:], x[6:_NV], tau_qp)
        errors = self._errors
        task_errors = {"com": errors[0], "base_orientation": errors[1], "posture": errors[2]}
        for leg in self._swing_legs:
            task_errors[f"{leg}_foot"] = errors[3 + _LEG_INDEX[leg]]
        t4 = time.perf_counter()
        return ControlOutput(
            **command, qdd=x[:_NV].copy(), forces=x[_F0:_S].reshape(_NC, 3).copy(),
            status=status, message=message,
            infeasible_group=group, task_errors=task_errors,
            timings={"model": t1 - t0, "assembly": t2 - t1, "solve": t3 - t2,
                     "total": t4 - t0},
        )

    def _update_model(self, q: np.ndarray, v: np.ndarray) -> None:
        model, data = self.model, self.data
        pin.computeAllTerms(model, data, q, v)  # M, h, joint Jacobians, com, Jcom, bias acc.
        pin.updateFramePlacements(model, data)
        pin.centerOfMass(model, data, pin.KinematicLevel.ACCELERATION, False)
        world = pin.LOCAL_WORLD_ALIGNED
        for i, fid in enumerate(self.contact_task.frame_ids):
            self._foot_pos[i] = data.oMf[fid].translation
            self._foot_acc[i] = pin.getFrameClassicalAcceleration(model, data, fid, world).vector
        self._q = q

    # ------------------------------------------------------------------ QP assembly

    def _build_problem(self) -> None:
        """Allocate the QP once and fill its constant entries."""
        cfg = self.config
        p = QpProblem(_N, _M)
        mu = cfg.friction_coefficient
        for i in range(_NC):
            fx = _F0 + 3 * i
            for axis in range(2):
                row = _FRIC.start + 4 * i + 2 * axis
                p.A[row, fx + axis], p.A[row, fx + 2] = 1.0, -mu      # f_t - mu f_z <= 0
                p.upper[row] = 0.0
                p.A[row + 1, fx + axis], p.A[row + 1, fx + 2] = 1.0, mu  # f_t + mu f_z >= 0
                p.lower[row + 1] = 0.0
        p.A[_SUP, _S] = 1.0
        p.lb[_S], p.ub[_S] = 0.0, INFINITY
        p.is_equality[_DYN] = True
        for name, rows in _GROUPS:
            p.row_groups[rows] = [name] * (rows.stop - rows.start)
        self.problem = p
        diagonal = np.arange(_N)
        self._h_const = np.zeros((_N, _N))
        self._h_const[diagonal[:_NV], diagonal[:_NV]] = (cfg.acceleration_weight
                                                         + cfg.acceleration_rate_weight)
        self._h_const[diagonal[_F0:_S], diagonal[_F0:_S]] = cfg.force_weight + cfg.force_rate_weight
        self._h_const[_S, _S] = cfg.support_slack_weight
        self._rate_weights = np.concatenate([np.full(_NV, cfg.acceleration_rate_weight),
                                             np.full(3 * _NC, cfg.force_rate_weight)])
        self._x_prev = np.zeros(_S)
        # Per-tick inputs and outputs of the compiled assembly, allocated once.
        self._foot_pos = np.zeros((_NC, 3))
        self._foot_acc = np.zeros((_NC, 6))
        self._stance_flags = np.ones(_NC, dtype=np.bool_)
        self._foot_refs = np.zeros((_NC, 3, 3))
        self._foot_gains = np.zeros((_NC, 3))
        self._normals = np.zeros((4, 2))
        self._offsets = np.zeros(4)
        self._n_edges = 0
        self._jc = np.zeros((3 * _NC, _NV))
        self._errors = np.zeros(3 + _NC)
        self._base_error = np.zeros(3)
        self._base_integral = np.zeros(3)
        self._base_reference = np.zeros((3, 3))
        self._work_ms = np.zeros((_NV, _NV))
        self._work_foot_jac = np.zeros((_NC, 6, _NV))
        self._support_key: tuple[str, ...] | None = None
        self._swing_legs: list[str] = []

    def _contacts_changed(self) -> None:
        """Refresh what depends on the contact modes (not on the state)."""
        p, cfg = self.problem, self.config
        for i, leg in enumerate(LEGS):
            rows = slice(_CON.start + 3 * i, _CON.start + 3 * i + 3)
            fz = _F0 + 3 * i + 2
            self._stance_flags[i] = self._stance[leg]
            self.motor.set_stance(i, self._stance[leg])
            if self._stance[leg]:
                fmax = self._max_force[leg]
                p.is_equality[rows] = True
                p.lb[fz], p.ub[fz] = min(cfg.min_normal_force_n, fmax), fmax
                p.lb[fz - 2:fz], p.ub[fz - 2:fz] = -INFINITY, INFINITY
            else:
                p.is_equality[rows] = False
                p.lb[fz - 2:fz + 1] = p.ub[fz - 2:fz + 1] = 0.0
        self._swing_legs = [leg for leg in LEGS if not self._stance[leg]]
        self._support = tuple(self.support_legs())
        self._support_key = None
        p.structure_version += 1

    def _assemble(self, q: np.ndarray, v: np.ndarray) -> None:
        data, p, cfg = self.data, self.problem, self.config
        legs = self._support
        if legs != self._support_key:  # the polygon changes with the contacts only
            self._support_key = legs
            self._n_edges = 0
            if len(legs) >= 3:
                points = self._foot_pos[[_LEG_INDEX[leg] for leg in legs], :2]
                normals, offsets = self.support.halfplanes(points)
                self._n_edges = len(normals)
                self._normals[:self._n_edges], self._offsets[:self._n_edges] = normals, offsets
        for leg in self._swing_legs:
            task, i = self.foot_tasks[leg], _LEG_INDEX[leg]
            self._foot_refs[i] = task.reference
            self._foot_gains[i] = task.gains
        # Integral action on the base orientation: joint friction the model lacks holds
        # the base tilted when the proportional term alone needs less torque than it.
        # Only on four feet: with a foot up, a small tilt is the tasks' fair compromise,
        # and the integral would trade the raised foot's tracking for it; it then fades.
        ki = cfg.base_orientation_ki
        if ki:
            integral = self._base_integral
            if self._swing_legs or self._support != _ALL_LEGS:
                integral *= _INTEGRAL_FADE
            else:
                integral += cfg.control_period_s * self._base_error
                np.clip(integral, -cfg.base_orientation_integral_limit,
                        cfg.base_orientation_integral_limit, out=integral)
        np.copyto(self._base_reference, self.base_task.reference)
        if ki:
            self._base_reference[2] += ki * self._base_integral
        qp_kernel.assemble(
            data.M, data.nle, data.J, data.Jcom, data.com[0], data.vcom[0], data.acom[0],
            data.oMi[1].rotation, q, v, self._foot_pos, self._foot_acc, self._stance_flags,
            FOOT_RADIUS_M, self.contact_task.gains[1],
            self.com_task.reference, self.com_task.gains,
            self.base_task.rotation, self._base_reference, self.base_task.gains,
            self._base_error,
            self.posture_task.reference, self.posture_task.gains, self.posture_task.joint_weights,
            self._foot_refs, self._foot_gains,
            self._normals, self._offsets, self._n_edges, cfg.support_omega,
            self.tau_max, self._q_low, self._q_high, self._v_max, cfg.joint_limit_horizon_s,
            self._h_const, self._rate_weights, self._x_prev, self._tau_prev,
            cfg.torque_rate_weight, p.H, p.f, p.A, p.lower, p.upper, p.lb, p.ub, self._jc,
            self._errors, self._work_ms, self._work_foot_jac)

    # ------------------------------------------------------------------ failures

    def _static_torques(self, q: np.ndarray, gravity: np.ndarray) -> np.ndarray:
        """Torques that hold ``q`` at rest with the body's weight on the stance feet."""
        self.contact_task.update(self.model, self.data, q, np.zeros(_NV))
        rows = [r for i, leg in enumerate(LEGS) if self._stance[leg]
                for r in range(3 * i, 3 * i + 3)]
        jc = self.contact_task.jacobian[rows]
        forces = np.linalg.lstsq(jc[:, :6].T, gravity[:6], rcond=None)[0]
        self._x_prev[:] = 0.0
        self._x_prev[[_F0 + r for r in rows]] = forces
        return gravity[6:] - jc[:, 6:].T @ forces

    def safe_command(self, v: np.ndarray, message: str) -> ControlOutput:
        """The safe fallback command for velocity ``v``, with status FALLBACK and ``message``.

        For a caller that finds a command unusable after the controller produced it (a guard
        in the control loop, a fault detected downstream).
        """
        return self._fallback(v, message, time.perf_counter())

    def _fallback(self, v: np.ndarray, message: str, t0: float, *,
                  group: str = "") -> ControlOutput:
        """Safe command: the last good torques with joint damping, inside the limits."""
        if not group:  # QP failures were counted where they happened
            self.failures += 1
        self.motor.reference.release()
        out = ControlOutput.damped_hold(
            self._tau_good, v, damping=self.config.fallback_damping, tau_max=self.tau_max,
            message=message, elapsed_s=time.perf_counter() - t0, group=group,
            q_joints=None if self._q is None else self._q[7:])
        self._tau_prev = out.tau
        return out

    @staticmethod
    def _fresh_solve(problem: QpProblem) -> QpResult:
        """Solve with a new DAQP workspace: tells a solver failure from infeasibility."""
        from wbc.backends.daqp_backend import DaqpBackend

        return DaqpBackend().solve(problem)

    def diagnose(self) -> tuple[str, QpResult | None]:
        """Name the constraint group that makes the current QP infeasible.

        Re-solves copies of the problem with one group relaxed at a time (off the hot path,
        only after a failure), limits before physics; the first group whose relaxation
        makes it solvable is named. Returns the name ('' if none) and, when that group is a
        limit (not physics), the relaxed problem's solution, usable as a command.
        """
        def rows(group: slice):
            def relax(trial: QpProblem) -> None:
                trial.lower[group], trial.upper[group] = -INFINITY, INFINITY
                trial.is_equality[group] = False
            return relax

        def normal_force(trial: QpProblem) -> None:  # never a pull on the floor
            trial.lb[_F0 + 2:_S:3] = np.minimum(trial.lb[_F0 + 2:_S:3], 0.0)
            trial.ub[_F0 + 2:_S:3] = np.where(trial.ub[_F0 + 2:_S:3] > 0.0, INFINITY, 0.0)

        def joint_limits(trial: QpProblem) -> None:
            trial.lb[6:_NV], trial.ub[6:_NV] = -INFINITY, INFINITY

        # Limits first: relaxing the physics (dynamics, stance contacts) would make almost
        # any problem feasible by letting the robot fall, which names nothing useful.
        groups = [("torque limits", rows(_TAU), True), ("normal force bounds", normal_force, True),
                  ("friction", rows(_FRIC), True), ("joint limits", joint_limits, True),
                  ("support polygon", rows(_SUP), True),
                  ("stance contacts", rows(_CON), False), ("dynamics", rows(_DYN), False)]
        for name, relax, usable in groups:
            trial = self.problem.copy()
            relax(trial)
            result = self._fresh_solve(trial)
            if result.found:
                return name, result if usable else None
        return "", None


def warm_up() -> None:
    """Compile (or load from numba's cache) the control tick's kernel, with one tick."""
    controller = WholeBodyController()
    q = controller.description.pose("standing")
    controller.reset(q)
    controller.step(q, np.zeros(_NV))
