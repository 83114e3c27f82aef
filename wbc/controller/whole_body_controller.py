"""The whole-body inverse-dynamics QP controller of the GO2."""

from __future__ import annotations

import math
import time
from typing import Any

import numba
import numpy as np
import pinocchio as pin

# The tasks' modules, not the package: `import tasks` imports wbc, and with it this module,
# before the package has any names (see wbc/__init__.py).
from tasks.base_orientation_task import BaseOrientationTask
from tasks.com_task import ComTask
from tasks.constraint import Constraint
from tasks.contact_task import ContactTask
from tasks.floating_base_dynamics import FloatingBaseDynamics
from tasks.frame_position_task import FramePositionTask
from tasks.friction_cones import FrictionCones
from tasks.joint_limits import JointLimits
from tasks.posture_task import PostureTask
from tasks.stance_contacts import StanceContacts
from tasks.support_polygon_barrier import SupportPolygonBarrier
from tasks.task import Task
from tasks.torque_limits import TorqueLimits
from wbc.backends.backend import make_backend
from wbc.backends.qp_problem import INFINITY, QpProblem, QpResult
from wbc.controller.contact_modes import ContactModes
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.controller.controller_config import ControllerConfig, config_with_overrides
from wbc.controller.motor_command_shaper import MotorCommandShaper
from wbc.controller.problem_builder import ProblemBuilder, Regularization
from wbc.core.compiled_call import bind_compiled
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, LEGS, Go2Description
from wbc.model.kinematics import RobotKinematics
from wbc.model.support_polygon import SupportPolygon

_NV, _NJ, _NC = 18, 12, 4
_LEG_INDEX = {leg: i for i, leg in enumerate(LEGS)}
_ALL_LEGS = tuple(LEGS)
#: The loaded feet whose QP layouts :meth:`WholeBodyController.reset` prepares: all four,
#: and each foot raised.
_PREPARED_SUPPORTS = (_ALL_LEGS, *(tuple(leg for leg in LEGS if leg != up) for up in LEGS))
#: Per-tick decay of the orientation integral while not on four loaded feet (0.1 s).
_INTEGRAL_FADE = 0.99


@numba.njit(cache=True)
def _error_norms(com, base, posture, fl, fr, rl, rr):  # pragma: no cover - compiled
    """Euclidean norms of the built-in tasks' errors: CoM, base, posture, then the feet."""
    return (np.sqrt(com @ com), np.sqrt(base @ base), np.sqrt(posture @ posture),
            np.sqrt(fl @ fl), np.sqrt(fr @ fr), np.sqrt(rl @ rl), np.sqrt(rr @ rr))


class WholeBodyController(ContactModes):
    """Force-level whole-body control of the GO2 by one QP per tick, composed of tasks.

    Decision variables ``x = [qdd (18), f (3 per stance foot), s]``: generalized
    accelerations, world contact forces of the stance feet, and the slack of the
    support-polygon barrier (:class:`tasks.VariableLayout`). The cost is the weighted sum of
    the registered tasks (centre of mass, base orientation, swing feet, posture, and any
    :meth:`add_task` adds) plus small regularisations and a torque-rate term; the
    constraints are the registered ones (:meth:`add_constraint`):

    - the floating-base rows of the equations of motion ``M_u qdd + h_u = J_u^T f``;
    - stance feet fixed: ``J_c qdd + Jdot_c v = -kd v_c``;
    - torque limits (a fraction of the URDF's) on ``tau = M_a qdd + h_a - J_a^T f``;
    - friction pyramids, with minimum and maximum normal force per stance foot (a foot
      being unloaded has its maximum ramped down by the caller);
    - joint position and velocity limits as acceleration bounds;
    - the centre of mass inside the support polygon with a margin, as a soft barrier.

    By default the first two (equalities) are eliminated exactly before the solve (see
    :mod:`wbc.controller.qp_kernel`): the solver sees about 13 variables and no equality rows, and the
    torques follow from the solution.

    Example:
        >>> controller = WholeBodyController()            # GO2, DAQP, default gains
        >>> controller.reset(q)                           # hold the current pose
        >>> out = controller.step(q, v)                   # 1 kHz
        >>> out.tau, out.status, out.timings["total"]
    """

    def __init__(self, config: ControllerConfig | None = None, *,
                 description: Go2Description | None = None,
                 extra_frames: tuple[str, ...] = (), **overrides: Any):
        """Args:
            config: All parameters (see :class:`ControllerConfig`); defaults when ``None``.
            description: The robot files (found automatically by default).
            extra_frames: Frames (besides the feet and the base) whose kinematics tasks added
                with :meth:`add_task` will read, e.g. ``("FR_calf",)``.
            **overrides: Fields of :class:`ControllerConfig` to change, e.g. ``backend="osqp"``.

        Raises:
            ConfigurationError: An override that is not a field of :class:`ControllerConfig`
                (the message names every unknown one and lists the fields), a value out of
                its range (the message names the field and the range), or an unknown frame
                in ``extra_frames``.
            UnknownNameError: A backend that is not installed (the message lists those that
                are).
        """
        self.config = cfg = config_with_overrides(config, overrides)
        self.description = description or Go2Description.default()
        self.model = self.description.build_model()
        self.data = self.model.createData()
        self.backend = make_backend(cfg.backend)
        tau_max = cfg.torque_limit_fraction * self.description.effort_limit
        frames = tuple(FOOT_FRAMES[leg] for leg in LEGS) + ("base",)
        for frame in extra_frames:
            if not self.model.existFrame(frame):
                names = [f.name for f in self.model.frames]
                raise ConfigurationError(
                    f"extra_frames: unknown frame {frame!r}; valid frames: {names}")
        frames += tuple(f for f in extra_frames if f not in frames)
        #: The robot's kinematics and dynamics at the last state (one compiled call a tick).
        self.kinematics = RobotKinematics(self.model, frames)
        self._feet_view = self.kinematics.frame_position[:len(LEGS)]
        self._feet_view.flags.writeable = False

        self.com_task = ComTask(kp=cfg.com_kp, weight=cfg.com_weight)
        self.base_task = BaseOrientationTask(kp=cfg.base_orientation_kp,
                                             weight=cfg.base_orientation_weight)
        self.posture_task = PostureTask(kp=cfg.posture_kp, weight=cfg.posture_weight)
        self.foot_tasks = {leg: FramePositionTask(self.model, FOOT_FRAMES[leg], kp=cfg.foot_kp,
                                                  weight=cfg.foot_weight) for leg in LEGS}
        self.contact_task = ContactTask(self.model, [FOOT_FRAMES[leg] for leg in LEGS],
                                        kd=cfg.contact_damping, radius_m=FOOT_RADIUS_M)
        self.support = SupportPolygon(margin_m=cfg.support_margin_m)
        self.friction = FrictionCones(_NC, mu=cfg.friction_coefficient,
                                      min_force_n=cfg.min_normal_force_n,
                                      max_force_n=cfg.max_normal_force_n)
        self.support_barrier = SupportPolygonBarrier(omega=cfg.support_omega)
        self.torque_limits = TorqueLimits(self.contact_task, tau_max)
        leg_columns = np.array([[6 + j for j in self.description.leg_joint_indices(leg)]
                                for leg in LEGS])
        #: Stacks the registered tasks and constraints into the tick's QP.
        self.builder = ProblemBuilder(
            self.kinematics, self.contact_task, LEGS, leg_columns=leg_columns,
            reduce=cfg.eliminate_dynamics,
            regularization=Regularization(
                acceleration=cfg.acceleration_weight, force=cfg.force_weight,
                acceleration_rate=cfg.acceleration_rate_weight,
                force_rate=cfg.force_rate_weight, torque_rate=cfg.torque_rate_weight,
                slack={"support": cfg.support_slack_weight}))
        for task in (self.com_task, self.base_task, self.posture_task):
            self.builder.add_task(task)
        for task in self.foot_tasks.values():
            self.builder.add_task(task, active=False)
        for constraint in (FloatingBaseDynamics(self.contact_task),
                           StanceContacts(self.contact_task), self.torque_limits,
                           self.friction,
                           JointLimits(self.description.position_lower,
                                       self.description.position_upper,
                                       self.description.velocity_limit,
                                       horizon_s=cfg.joint_limit_horizon_s),
                           self.support_barrier):
            self.builder.add_constraint(constraint)

        self.motor = MotorCommandShaper(cfg, tau_max=tau_max,
                                        effort_limit=self.description.effort_limit)
        self._init_contact_modes()
        self._support_key: tuple[str, ...] | None = None
        self._swing_legs: list[str] = []
        self._base_integral = np.zeros(3)
        self._contacts_changed()
        self._tau_good = np.zeros(_NJ)
        self._q: np.ndarray | None = None
        self.ticks = 0
        self.failures = 0
        self._forces = np.zeros((_NC, 3))
        # The tasks' error arrays are never re-bound: their norms' call is bound once.
        self._error_norms = bind_compiled(
            _error_norms, self.com_task.error, self.base_task.error, self.posture_task.error,
            *(self.foot_tasks[leg].error for leg in LEGS))

    @property
    def tau_max(self) -> np.ndarray:
        """The QP's torque limits [N m] (12,), description order."""
        return self.torque_limits.tau_max

    @tau_max.setter
    def tau_max(self, value: np.ndarray) -> None:
        self.torque_limits.tau_max = value  # validated; the QP's rows read it in place
        self.motor.tau_max[:] = self.torque_limits.tau_max  # and the feed-forward's clip

    # ------------------------------------------------------------------ composition

    def add_task(self, task: Task) -> Task:
        """Add a task of your own to the QP's cost (from the next tick); returns it.

        The task reads :attr:`kinematics` (the frames it names must be among the
        controller's: pass them as ``extra_frames``). Example: ``examples/custom_task.py``.
        """
        return self.builder.add_task(task)

    def remove_task(self, task: Task) -> None:
        """Remove a task added with :meth:`add_task`."""
        if task in (self.com_task, self.base_task, self.posture_task,
                    *self.foot_tasks.values()):
            raise ConfigurationError(f"task: {type(task).__name__} is built in; set its weight "
                                     "to 0 to take it out of the cost")
        self.builder.remove_task(task)

    def add_constraint(self, constraint: Constraint) -> Constraint:
        """Add a constraint of your own to the QP (from the next tick); returns it."""
        return self.builder.add_constraint(constraint)

    def remove_constraint(self, constraint: Constraint) -> None:
        """Remove a constraint added with :meth:`add_constraint`."""
        self.builder.remove_constraint(constraint)

    @property
    def tasks(self) -> list[Task]:
        """The registered tasks (built-in first)."""
        return list(self.builder.tasks)

    @property
    def constraints(self) -> list[Constraint]:
        """The registered constraints (built-in first)."""
        return list(self.builder.constraints)

    @property
    def problem(self) -> QpProblem:
        """The full QP over ``x`` as last updated (its cost is filled on demand)."""
        return self.builder.problem

    @property
    def last_solution(self) -> np.ndarray:
        """The last solved QP's ``x`` in the current layout (zeros before any)."""
        return self.builder.solution

    # ------------------------------------------------------------------ references

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: every target is set from it, all four feet in stance.

        The base orientation target keeps the current yaw with zero roll and pitch.
        """
        q = as_vector("q", q, self.model.nq)
        v = np.zeros(_NV) if v is None else as_vector("v", v, _NV)
        kin = self.kinematics
        kin.update(q, v)
        self._q = q
        self.com_task.set_target(kin.com_position)
        yaw = pin.rpy.matrixToRpy(kin.base_rotation)[2]
        self.base_task.set_rpy(0.0, 0.0, yaw)
        self.posture_task.set_target(q[7:])
        for leg, task in self.foot_tasks.items():
            task.set_target(kin.frame_position[_LEG_INDEX[leg]])
        for leg in LEGS:
            self._stance[leg] = True
            self._max_force[leg] = self.config.max_normal_force_n
            self.foot_tasks[leg].set_weight(self.config.foot_weight)
        self.posture_task.set_joint_weights(np.ones(_NJ))
        self._base_integral[:] = 0.0
        self._contacts_changed()
        tau, forces = self._static_torques(q)
        self.builder.tau_prev[:] = tau
        self._tau_good = tau.copy()
        x_prev = np.zeros(self.builder.layout.n)
        for leg in LEGS:
            x_prev[self.builder.layout.force_slice(leg)] = forces[_LEG_INDEX[leg]]
        self.builder.reset_rates(x_prev)
        self.motor.reference.reset(q[7:], v[6:])
        self.backend.setup(self.builder.assemble_full())
        # The layouts a raised or landed foot switches to, with their compiled calls and
        # solver structures, made now: made on first use they cost milliseconds, at the
        # very tick the foot leaves or touches the ground.
        for problem in self.builder.prepare(_PREPARED_SUPPORTS):
            self.backend.prepare(problem)

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass target [m], velocity [m/s] and feed-forward acceleration [m/s^2]."""
        self.com_task.set_motion(position, velocity, acceleration)

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target [rad] (12,), description order (a copy)."""
        return self.posture_task._require_target().copy()

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture target [rad], velocity [rad/s] and feed-forward [rad/s^2] (12,)."""
        self.posture_task.set_motion(joint_positions, velocity, acceleration)

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
        return self.kinematics.com_position.copy()

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity [m/s] at the last state."""
        return self.kinematics.com_velocity.copy()

    def foot_position(self, leg: str) -> np.ndarray:
        """World position [m] of a foot frame (sphere centre) at the last state."""
        check_name("leg", leg, LEGS)
        return self.kinematics.frame_position[_LEG_INDEX[leg]].copy()

    def foot_positions(self) -> np.ndarray:
        """World positions (4, 3) [m] of the foot frames at the last state, ``LEGS`` order.

        A read-only view that the next tick updates: copy it to keep it.
        """
        return self._feet_view

    def foot_target(self, leg: str) -> np.ndarray | None:
        """A foot's world position target [m] (a copy; ``None`` before one is set). It is
        tracked while the leg swings."""
        check_name("leg", leg, LEGS)
        return self.foot_tasks[leg].target

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
        self.foot_tasks[leg].set_motion(position, velocity, acceleration)

    def _contact_mode_changed(self, leg: str) -> None:
        i = _LEG_INDEX[leg]
        if self._stance[leg] == self._stance_applied[i]:
            # Only a force bound changed (a foot being unloaded or reloaded, every tick):
            # the layout and the gains stay; the polygon changes when the support set does.
            self.friction.max_force[i] = self._max_force[leg] if self._stance[leg] else 0.0
            support = tuple(self.support_legs())
            if support != self._support:
                self._support, self._support_key = support, None
            return
        self._contacts_changed()

    def _base_placement(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self._q is None:
            return None
        return self.kinematics.base_rotation, self.kinematics.base_position  # read-only

    def normal_force(self, leg: str) -> float:
        """The normal force [N] the last solved tick gave a foot (0 before any)."""
        check_name("leg", leg, LEGS)
        value = self._forces[_LEG_INDEX[leg], 2]
        return float(value) if math.isfinite(value) else 0.0

    # ------------------------------------------------------------------ the tick

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick: kinematics, tasks and constraints, QP assembly, solve.

        Never raises on bad numbers in the state or a failed solve: it returns the safe
        fallback command (joint damping around the last good torques) with status
        ``FALLBACK`` and a message, and stays usable for the next tick.
        """
        t0 = time.perf_counter()
        self.ticks += 1
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        if q.shape != (19,) or v.shape != (_NV,):
            return self._fallback(v, f"state: expected q {(self.model.nq,)} and v {(_NV,)}, "
                                     f"received {q.shape} and {v.shape}", t0)
        if not self.kinematics.update(q, v):  # checks q and v are finite, in compiled code
            bad = [f"q[{i}]" for i in np.flatnonzero(~np.isfinite(q))]
            bad += [f"v[{i}]" for i in np.flatnonzero(~np.isfinite(v))]
            return self._fallback(v, f"state: non-finite values at {', '.join(bad)}", t0)
        builder = self.builder
        self._q = q
        self._before_update()
        t1 = time.perf_counter()
        builder.update()
        problem = builder.assemble()
        t2 = time.perf_counter()
        result = self.backend.solve(problem)
        t3 = time.perf_counter()
        status, message, group = ControlStatus.OK, "", ""
        if not result.found:
            self.failures += 1
            message = f"QP failed: {result.reason}"
            full = builder.assemble_full()
            builder.reduced = False
            # The solver's workspace may hold a bad state after a failure.
            self.backend.setup(full)
            retry = self._fresh_solve(full)
            if retry.found:  # a solver failure, not an infeasible problem
                result, status = retry, ControlStatus.RESOLVED
                message += "; the problem is feasible: commanded a fresh DAQP solution"
            else:
                group, relaxed = self._blame(full)
                if group:
                    message += f"; infeasible constraint group: {group}"
                if relaxed is None:
                    return self._fallback(v, message, t0, group=group)
                result, status = relaxed, ControlStatus.RELAXED
                message += "; commanded the solution with that group relaxed"
        forces = np.empty((_NC, 3))
        x, tau_qp = builder.accept(result.x, forces)
        if status is not ControlStatus.OK:
            np.clip(tau_qp, -self.tau_max, self.tau_max, out=tau_qp)
        builder.tau_prev[:] = tau_qp
        self._tau_good = tau_qp
        self._forces = forces
        command = self.motor.shape(q[7:], v[6:], x[6:_NV], tau_qp)
        norms = self._error_norms()
        task_errors = {"com": norms[0], "base_orientation": norms[1], "posture": norms[2]}
        for leg in self._swing_legs:
            task_errors[leg + "_foot"] = norms[3 + _LEG_INDEX[leg]]
        t4 = time.perf_counter()
        return ControlOutput(
            **command, qdd=x[:_NV].copy(), forces=forces,
            status=status, message=message,
            infeasible_group=group, task_errors=task_errors,
            timings={"model": t1 - t0, "assembly": t2 - t1, "solve": t3 - t2,
                     "total": t4 - t0},
        )

    def _before_update(self) -> None:
        """Per-tick inputs that depend on the state: polygon, integral, force bounds."""
        legs = self._support
        if legs != self._support_key:  # the polygon changes with the contacts only
            self._support_key = legs
            if len(legs) >= 3:
                points = self.kinematics.frame_position[[_LEG_INDEX[leg] for leg in legs], :2]
                self.support_barrier.set_polygon(*self.support.halfplanes(points))
            else:
                self.support_barrier.set_polygon(np.zeros((0, 2)), np.zeros(0))
        # Integral action on the base orientation: joint friction the model lacks holds
        # the base tilted when the proportional term alone needs less torque than it.
        # Only on four feet: with a foot up, a small tilt is the tasks' fair compromise,
        # and the integral would trade the raised foot's tracking for it; it then fades.
        cfg = self.config
        ki = cfg.base_orientation_ki
        if ki:
            integral = self._base_integral
            if self._swing_legs or self._support != _ALL_LEGS:
                integral *= _INTEGRAL_FADE
            else:
                integral += cfg.control_period_s * self.base_task.error
                np.clip(integral, -cfg.base_orientation_integral_limit,
                        cfg.base_orientation_integral_limit, out=integral)
            np.multiply(ki, integral, out=self.base_task.bias)

    def _contacts_changed(self) -> None:
        """Refresh what depends on the contact modes (not on the state)."""
        for i, leg in enumerate(LEGS):
            self.motor.set_stance(i, self._stance[leg])
            self.friction.max_force[i] = self._max_force[leg] if self._stance[leg] else 0.0
            self.builder.set_active(self.foot_tasks[leg], not self._stance[leg])
        self._stance_applied = [self._stance[leg] for leg in LEGS]
        self._swing_legs = [leg for leg in LEGS if not self._stance[leg]]
        self.builder.set_loaded_contacts([leg for leg in LEGS if self._stance[leg]])
        self._support = tuple(self.support_legs())
        self._support_key = None

    # ------------------------------------------------------------------ failures

    def _static_torques(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Torques that hold ``q`` at rest with the body's weight on the stance feet, and the
        feet's forces (4, 3)."""
        self.kinematics.update(q, np.zeros(_NV))
        self.contact_task.update(self.kinematics)
        gravity = self.kinematics.nonlinear_effects.copy()
        stance = [i for i, leg in enumerate(LEGS) if self._stance[leg]]
        rows = [r for i in stance for r in range(3 * i, 3 * i + 3)]
        jc = self.contact_task.jacobian[rows]
        solved = np.linalg.lstsq(jc[:, :6].T, gravity[:6], rcond=None)[0]
        forces = np.zeros((_NC, 3))
        forces[stance] = solved.reshape(-1, 3)
        return gravity[6:] - jc[:, 6:].T @ solved, forces

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
        self.builder.tau_prev[:] = out.tau
        return out

    @staticmethod
    def _fresh_solve(problem: QpProblem) -> QpResult:
        """Solve with a new DAQP workspace: tells a solver failure from infeasibility."""
        from wbc.backends.daqp_backend import DaqpBackend

        return DaqpBackend().solve(problem)

    def diagnose(self) -> tuple[str, QpResult | None]:
        """Name the constraint group that makes the current QP infeasible, if one does.

        First solves the full problem (with a fresh DAQP workspace): a feasible problem
        names nothing, and the result is ``("", None)``; a failed solve of a feasible problem
        is the solver's failure, not a constraint's. Only an infeasible problem is searched:
        copies of it are re-solved with one group relaxed at a time (off the hot path),
        limits before physics, and the first group whose relaxation makes it solvable is
        named. Returns the name ('' if none) and, when that group is a limit (not physics),
        the relaxed problem's solution, usable as a command.
        """
        problem = self.builder.assemble_full()
        self.builder.reduced = False
        if self._fresh_solve(problem).found:
            return "", None
        return self._blame(problem)

    def _blame(self, problem: QpProblem) -> tuple[str, QpResult | None]:
        """:meth:`diagnose` for a full ``problem`` already known to be infeasible."""
        layout = self.builder.layout
        groups = np.array(problem.row_groups)
        forces = slice(layout.force_start, layout.slack_start)

        def rows(name: str):
            selected = groups == name

            def relax(trial: QpProblem) -> None:
                trial.lower[selected], trial.upper[selected] = -INFINITY, INFINITY
                trial.is_equality[selected] = False
            return relax

        def normal_force(trial: QpProblem) -> None:  # never a pull on the floor
            fz = trial.lb[forces][2::3]
            trial.lb[forces.start + 2:forces.stop:3] = np.minimum(fz, 0.0)
            trial.ub[forces.start + 2:forces.stop:3] = INFINITY

        def joint_limits(trial: QpProblem) -> None:
            trial.lb[6:_NV], trial.ub[6:_NV] = -INFINITY, INFINITY

        # Limits first: relaxing the physics (dynamics, stance contacts) would make almost
        # any problem feasible by letting the robot fall, which names nothing useful.
        candidates = [("torque limits", rows("torque limits"), True),
                      ("normal force bounds", normal_force, True),
                      ("friction", rows("friction"), True), ("joint limits", joint_limits, True),
                      ("support polygon", rows("support polygon"), True)]
        builtin = {"dynamics", "stance contacts", "torque limits", "friction", "support polygon",
                   "joint limits"}
        candidates += [(name, rows(name), True) for name in dict.fromkeys(problem.row_groups)
                       if name and name not in builtin]
        candidates += [("stance contacts", rows("stance contacts"), False),
                       ("dynamics", rows("dynamics"), False)]
        for name, relax, usable in candidates:
            trial = problem.copy()
            relax(trial)
            result = self._fresh_solve(trial)
            if result.found:
                return name, result if usable else None
        return "", None


def warm_up() -> None:
    """Compile (or load from numba's cache) the control tick's kernels, with one tick."""
    controller = WholeBodyController()
    q = controller.description.pose("standing")
    controller.reset(q)
    controller.step(q, np.zeros(_NV))
