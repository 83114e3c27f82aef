"""The whole-body inverse-dynamics QP controller of the GO2, composed of its parts."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from wbc.backends.backend import make_backend
from wbc.backends.qp_problem import QpResult
from wbc.controller.balance_problem import BalanceProblem
from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.controller.controller_config import ControllerConfig, config_with_overrides
from wbc.controller.foot_reach import FootReach
from wbc.controller.motor_command_shaper import MotorCommandShaper, joint_types
from wbc.controller.qp_recovery import QpRecovery
from wbc.controller.task_composition import TaskComposition
from wbc.controller.tick_plan import TickPlan
from wbc.core.compiled_program import Step
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, JOINT_NAMES, LEGS, Go2Description
from wbc.model.kinematics import RobotKinematics


class WholeBodyController(TaskComposition):
    """Force-level whole-body control of the GO2 by one QP per tick, composed of parts:
    :attr:`schedule` (:class:`ContactSchedule`: which feet stand, their force bounds and
    ramps), :attr:`balance` (:class:`BalanceProblem`: the built-in tasks and constraints on
    :attr:`builder`, a :class:`ProblemBuilder`, with any :meth:`add_task` and
    :meth:`add_constraint` add), :attr:`backend` (solves the QP), :attr:`recovery`
    (:class:`QpRecovery`: when it fails) and :attr:`motor` (:class:`MotorCommandShaper`:
    the command).

    The QP is over ``x = [qdd (nv), f (3 per stance foot), s]`` (:class:`tasks.VariableLayout`);
    by default the floating-base dynamics and the stance contacts, which declare themselves
    eliminable (:class:`tasks.Elimination`), are eliminated before the solve
    (:mod:`wbc.controller.qp_kernel`): the solver sees about 13 variables, no equalities.

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
            **overrides: Parts of :class:`ControllerConfig` to change (a part, or a mapping of
                some of its fields), e.g. ``solver={"backend": "osqp"}``.

        Raises:
            ConfigurationError: Overrides that are not parts (each named, the parts
                listed; a bare parameter name with its path), a value out of its range (the
                field and range named), an unknown frame in ``extra_frames``.
            UnknownNameError: A backend that is not installed (the installed ones listed).
        """
        self.config = cfg = config_with_overrides(config, overrides)
        self.description = description or Go2Description.default()
        self.model = model = self.description.build_model()
        self._nq, self._nv = model.nq, model.nv  # read every tick: Python ints, not pybind
        self.backend = make_backend(cfg.solver.backend)
        self.legs = legs = tuple(LEGS)
        feet = tuple(FOOT_FRAMES[leg] for leg in legs)
        for frame in extra_frames:
            if not model.existFrame(frame):
                names = [f.name for f in model.frames]
                raise ConfigurationError(
                    f"extra_frames: unknown frame {frame!r}; valid frames: {names}")
        frames = feet + ("base",)
        frames += tuple(f for f in extra_frames if f not in frames)
        #: The robot's kinematics and dynamics at the last state (one compiled call a tick).
        self.kinematics = RobotKinematics(model, frames)
        self._feet_view = self.kinematics.frame_position[:len(legs)]
        self._feet_view.flags.writeable = False
        self._leg_index = {leg: i for i, leg in enumerate(legs)}
        self._leg_joints = [self.description.leg_joint_indices(leg) for leg in legs]

        period_s = cfg.solver.control_period_s
        self.schedule = ContactSchedule(legs, cfg.contacts, control_period_s=period_s,
                                        listener=self._contact_changed)
        self.reach = FootReach(self.description, legs)
        self.balance = BalanceProblem(self.description, model, self.kinematics, cfg, legs=legs,
                                      foot_frames=feet, foot_radius_m=FOOT_RADIUS_M,
                                      normal_force_bounds=self.schedule.bounds)
        #: Stacks the registered tasks and constraints into the tick's QP.
        self.builder = self.balance.builder
        self.com_task, self.base_task = self.balance.com_task, self.balance.base_task
        self.posture_task, self.foot_tasks = self.balance.posture_task, self.balance.foot_tasks
        self.contact_task = self.balance.contact_task
        self.motor = MotorCommandShaper(cfg.shaping, control_period_s=period_s,
                                        tau_max=self.balance.torque_limits.tau_max,
                                        effort_limit=self.description.effort_limit,
                                        joint_types=joint_types(JOINT_NAMES))
        # The measured joint state as the kinematics holds it (views updated in place): what
        # the motor command's shaping reads inside the compiled solve.
        self._q_joints, self._v_joints = self.kinematics.q[7:], self.kinematics.v[6:]
        self.builder.set_after_solve(self._after_solve)
        self.recovery = QpRecovery(cfg.solver.backend, self.builder, motor=self.motor,
                                   torque_limits=self.balance.torque_limits,
                                   damping=cfg.shaping.fallback_damping)
        #: The sets of loaded feet whose plans :meth:`reset` makes ready: all of them, each
        #: foot raised, and a trot's diagonal pairs (a foot leaving or touching the ground
        #: never waits for one).
        self.prepared_supports: tuple[tuple[str, ...], ...] = (
            legs, *(tuple(leg for leg in legs if leg != up) for up in legs),
            (legs[0], legs[3]), (legs[1], legs[2]))
        self._q: np.ndarray | None = None
        self._contact_changed()
        self.ticks = 0
        self.failures = 0
        self._forces = np.zeros((len(legs), 3))

    @property
    def control_period_s(self) -> float:
        """The period [s] the controller runs at (its motor command integrates over it)."""
        return self.config.solver.control_period_s

    @property
    def tau_max(self) -> np.ndarray:
        """The QP's torque limits [N m] (nv - 6,), description order."""
        return self.balance.torque_limits.tau_max

    @tau_max.setter
    def tau_max(self, value: np.ndarray) -> None:
        self.balance.torque_limits.tau_max = value  # validated; the QP's rows read it in place
        self.motor.tau_max[:] = self.balance.torque_limits.tau_max  # and the feed-forward's

    # ------------------------------------------------------------------ references

    def reset(self, q: np.ndarray, v: np.ndarray | None = None) -> None:
        """Hold the given state: every target is set from it, every foot in stance.

        The base orientation target keeps the current yaw with zero roll and pitch.
        """
        nv = self.model.nv
        q = as_vector("q", q, self.model.nq)
        v = np.zeros(nv) if v is None else as_vector("v", v, nv)
        self.kinematics.compute(q, v)
        self._q = q
        self.balance.hold(q)
        self.schedule.reset()
        self._contact_changed()
        self.recovery.tau_good = self.balance.hold_at_rest(q)
        self.motor.reference.reset(q[7:], v[6:])
        self.backend.setup(self.builder.assemble_full())
        # The layouts a raised or landed foot switches to, with their compiled calls and
        # solver structures, made now: made on first use they cost milliseconds, at the
        # very tick the foot leaves or touches the ground.
        self.builder.prepare(self.prepared_supports, swing_tasks=self.foot_tasks,
                             backend=self.backend)

    def set_com_target(self, position: np.ndarray, velocity: np.ndarray | None = None,
                       acceleration: np.ndarray | None = None) -> None:
        """Centre-of-mass target [m], velocity [m/s] and feed-forward acceleration [m/s^2]."""
        self.com_task.set_motion(position, velocity, acceleration)

    @property
    def com_target(self) -> np.ndarray:
        """The current centre-of-mass target [m] (a copy)."""
        return self.com_task._require_target().copy()

    @property
    def posture_target(self) -> np.ndarray:
        """Joint posture target [rad] (nv - 6,), description order (a copy)."""
        return self.posture_task._require_target().copy()

    def set_posture_target(self, joint_positions: np.ndarray,
                           velocity: np.ndarray | None = None,
                           acceleration: np.ndarray | None = None) -> None:
        """Joint posture target [rad], velocity [rad/s] and feed-forward [rad/s^2]."""
        self.posture_task.set_motion(joint_positions, velocity, acceleration)

    def set_posture_weights(self, weights: np.ndarray) -> None:
        """Per-joint multipliers of the posture weight; ones restore the default."""
        self.posture_task.set_joint_weights(weights)

    def set_foot_weight(self, leg: str, weight: float | None = None) -> None:
        """Weight of a swing foot's position task (0 hands the leg to the posture task;
        ``None`` restores the configured ``foot_weight``)."""
        check_name("leg", leg, self.legs)
        self.foot_tasks[leg].set_weight(self.config.weights.foot_weight if weight is None
                                        else weight)

    def foot_target(self, leg: str) -> np.ndarray | None:
        """A foot's world position target [m] (a copy; ``None`` before one is set). It is
        tracked while the leg swings."""
        check_name("leg", leg, self.legs)
        return self.foot_tasks[leg].target

    def set_foot_target(self, leg: str, position: np.ndarray,
                        velocity: np.ndarray | None = None,
                        acceleration: np.ndarray | None = None, *,
                        clamp_to_reach: bool = False) -> None:
        """World target [m], velocity [m/s] and feed-forward acceleration of a foot,
        tracked while the leg swings. With ``clamp_to_reach`` a target beyond the leg's
        reach is moved onto it (motion generators that must never stop) instead of raising.

        Raises:
            ReachabilityError: The target is farther than :data:`LEG_REACH_M` from the leg's
                shoulder at the last state; the target is left unchanged.
        """
        position = self.reach.reachable_target(leg, position, self._base_placement(),
                                               clamp=clamp_to_reach)
        self.foot_tasks[leg].set_motion(position, velocity, acceleration)

    # ------------------------------------------------------------------ read-outs

    def com_position(self) -> np.ndarray:
        """Centre of mass [m] at the last state."""
        return self.kinematics.com_position.copy()

    def com_velocity(self) -> np.ndarray:
        """Centre-of-mass velocity [m/s] at the last state."""
        return self.kinematics.com_velocity.copy()

    def foot_position(self, leg: str) -> np.ndarray:
        """World position [m] of a foot frame (sphere centre) at the last state."""
        check_name("leg", leg, self.legs)
        return self.kinematics.frame_position[self._leg_index[leg]].copy()

    def foot_positions(self) -> np.ndarray:
        """World positions (legs, 3) [m] of the foot frames at the last state, legs' order.

        A read-only view that the next tick updates: copy it to keep it.
        """
        return self._feet_view

    def shoulder_position(self, leg: str) -> np.ndarray:
        """World position [m] of a leg's shoulder (fixed to the base) at the last state."""
        return self.reach.shoulder_position(leg, self._base_placement())

    def normal_force(self, leg: str) -> float:
        """The normal force [N] the last solved tick gave a foot (0 before any)."""
        check_name("leg", leg, self.legs)
        value = float(self._forces[self._leg_index[leg], 2])
        return value if np.isfinite(value) else 0.0

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

    def _base_placement(self) -> tuple[np.ndarray, np.ndarray] | None:
        if self._q is None:
            return None
        return self.kinematics.base_rotation, self.kinematics.base_position  # read-only

    # ------------------------------------------------------------------ contacts

    def _contact_changed(self, leg: str | None = None) -> None:
        """The schedule's listener: a foot's mode or bound changed (every foot: ``None``)."""
        balance = self.balance
        before = balance.stance  # follow replaces the list when a mode changed
        if balance.follow(self.schedule, leg, started=self._q is not None):
            every = leg is None or len(before) != len(balance.stance)
            for joints, standing, was in zip(self._leg_joints, balance.stance,
                                             balance.stance if every else before):
                if every or standing != was:  # the legs whose mode changed (each, at a reset)
                    self.motor.set_stance(joints, standing)

    # ------------------------------------------------------------------ the tick

    def step(self, q: np.ndarray, v: np.ndarray) -> ControlOutput:
        """One control tick: the schedule's ramps, kinematics, tasks and constraints, QP
        assembly, solve, motor command. Never raises on bad numbers in the state or a
        failed solve: it returns the safe fallback command (joint damping around the last
        good torques) with status ``FALLBACK`` and a message, and stays usable."""
        t0 = time.perf_counter()
        self.ticks += 1
        self.schedule.advance()
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        nq, nv = self._nq, self._nv
        if q.shape != (nq,) or v.shape != (nv,):
            return self._fallback(v, f"state: expected q {(nq,)} and v {(nv,)}, "
                                     f"received {q.shape} and {v.shape}", t0)
        if not self.kinematics.compute_vectors(q, v):  # checks they are finite, compiled
            bad = [f"q[{i}]" for i in np.flatnonzero(~np.isfinite(q))]
            bad += [f"v[{i}]" for i in np.flatnonzero(~np.isfinite(v))]
            return self._fallback(v, f"state: non-finite values at {', '.join(bad)}", t0)
        builder = self.builder
        self._q = q
        self.balance.before_update()
        t1 = time.perf_counter()
        problem = builder.build()
        t2 = time.perf_counter()
        # Solved, accepted, the motor command shaped and the error norms computed in one
        # compiled call where the backend allows it; else (and on a failure, solved again to
        # name it) through the backend's solve.
        self.motor.prepare(self._q_joints, self._v_joints)
        solved, status, message, group = builder.solve(self.backend), ControlStatus.OK, "", ""
        t3 = time.perf_counter()
        if solved is not None:
            x, tau_qp, forces = solved
            command = self.motor.command()
            task_errors = self.balance.task_errors(self.balance.swing_legs, computed=True)
        else:
            result = self.backend.solve(problem)
            t3 = time.perf_counter()
            if not result.found:
                self.failures += 1
                self.backend.setup(problem)  # a fresh workspace: the solver's may be bad now
                recovered, status, message, group = self.recovery.recover(result)
                if recovered is None:
                    return self._fallback(v, message, t0, group=group)
                result = recovered
            forces = np.empty((len(self.legs), 3))
            x, tau_qp = builder.accept(result.x, forces)
            if status is not ControlStatus.OK:
                np.clip(tau_qp, -self.tau_max, self.tau_max, out=tau_qp)
            builder.tau_prev[:] = tau_qp
            shaped = self.motor.shape(q[7:], v[6:], x[6:nv], tau_qp)
            command = (shaped["q_des"], shaped["dq_des"], shaped["kp"], shaped["kd"],
                       shaped["tau_ff"], shaped["tau"])
            task_errors = self.balance.task_errors(self.balance.swing_legs)
        self.recovery.tau_good = tau_qp
        self._forces = forces
        t4 = time.perf_counter()
        q_des, dq_des, kp, kd, tau_ff, tau = command
        return ControlOutput(
            q_des=q_des, dq_des=dq_des, kp=kp, kd=kd, tau_ff=tau_ff, tau=tau,
            qdd=x[:nv].copy(), forces=forces, status=status, message=message,
            infeasible_group=group, task_errors=task_errors,
            timings={"model": t1 - t0, "assembly": t2 - t1, "solve": t3 - t2,
                     "total": t4 - t0})

    def _after_solve(self, plan: TickPlan) -> list[Step]:
        """What the compiled solve of ``plan``'s layout runs once it accepted a solution:
        the motor command's shaping and the built-in tasks' error norms."""
        nv = self._nv
        return [self.motor.compiled_step(self._q_joints, self._v_joints, plan.x[6:nv],
                                         plan.tau),
                self.balance.error_norms_step()]

    # ------------------------------------------------------------------ failures

    def safe_command(self, v: np.ndarray, message: str) -> ControlOutput:
        """The safe fallback command for velocity ``v``, with status FALLBACK and ``message``,
        for a caller that finds a command unusable after the controller produced it (a guard
        in the control loop, a fault detected downstream)."""
        return self._fallback(v, message, time.perf_counter())

    def _fallback(self, v: np.ndarray, message: str, t0: float, *,
                  group: str = "") -> ControlOutput:
        """Safe command: the last good torques with joint damping, inside the limits."""
        if not group:  # QP failures were counted where they happened
            self.failures += 1
        return self.recovery.fallback(v, message, time.perf_counter() - t0, group=group,
                                      q_joints=None if self._q is None else self._q[7:])

    def diagnose(self) -> tuple[str, QpResult | None]:
        """Name the constraint group that makes the current QP infeasible, if one does
        (:meth:`QpRecovery.diagnose`): ``("", None)`` on a feasible QP, else the group and,
        when it is a limit (not physics), the relaxed problem's solution."""
        return self.recovery.diagnose()


def warm_up() -> None:
    """Compile (or load from numba's cache) the control tick's kernels, with one tick."""
    controller = WholeBodyController()
    q = controller.description.pose("standing")
    controller.reset(q)
    controller.step(q, np.zeros(controller.model.nv))
