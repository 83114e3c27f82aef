"""What the controller does when a tick's QP fails: a fresh solve, then naming the culprit."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tasks.torque_limits import TorqueLimits
from wbc.backends.backend import QpBackend, available_backends, make_backend
from wbc.backends.qp_problem import INFINITY, QpProblem, QpResult
from wbc.controller.control_output import ControlOutput, ControlStatus
from wbc.controller.motor_command_shaper import MotorCommandShaper
from wbc.controller.problem_builder import ProblemBuilder

#: The constraint groups the controller registers itself (others are a user's).
_BUILTIN_GROUPS = {"dynamics", "stance contacts", "torque limits", "friction",
                   "support polygon", "joint limits", "joint torques"}


class QpRecovery:
    """What the controller commands when a tick has no solution of its own.

    After the backend fails on a tick's QP: re-solve the full QP with a fresh workspace
    of the configured backend (a spent workspace is the usual cause of a solver failure on
    a feasible problem), and when that fails too, name the constraint group that makes the
    QP infeasible by relaxing one group at a time. With nothing usable (or a bad state):
    the safe fallback, the last good torques with joint damping (:meth:`fallback`).

    The search solves with DAQP whatever the configured backend: an active-set method
    answers "infeasible" exactly, where a first-order method (OSQP) only detects it to a
    tolerance and after many iterations, and DAQP solves each of the up to ten relaxed
    copies of these small dense QPs in tens of microseconds. Without DAQP installed, the
    configured backend searches.
    """

    def __init__(self, backend_name: str, builder: ProblemBuilder, *,
                 motor: MotorCommandShaper, torque_limits: TorqueLimits, damping: float):
        """Args:
            backend_name: The configured backend's registry name (fresh ones are made).
            builder: The problem builder whose QPs fail.
            motor: The motor command's shaper (its reference is released on a fallback).
            torque_limits: The QP's torque limits (the fallback stays inside them).
            damping: Joint damping of the fallback [N m s/rad].
        """
        self.backend_name = backend_name
        self.builder = builder
        self.motor = motor
        self.torque_limits = torque_limits
        self.damping = damping
        #: The last good torques [N m] (the controller records each solved tick's).
        self.tau_good = np.zeros(builder.nv - 6)
        self._searcher = "daqp" if "daqp" in available_backends() else backend_name

    def fallback(self, v: np.ndarray, message: str, elapsed_s: float, *, group: str = "",
                 q_joints: np.ndarray | None = None) -> ControlOutput:
        """The safe command: the last good torques with joint damping, inside the limits
        (:meth:`ControlOutput.damped_hold`); the torque-rate cost starts from it."""
        self.motor.reference.release()
        out = ControlOutput.damped_hold(
            self.tau_good, v, damping=self.damping, tau_max=self.torque_limits.tau_max,
            message=message, elapsed_s=elapsed_s, contacts=len(self.builder.contacts),
            group=group, q_joints=q_joints)
        self.builder.tau_prev[:] = out.tau
        return out

    def fresh_solve(self, problem: QpProblem) -> tuple[QpResult, str]:
        """Solve ``problem`` with a new workspace of the configured backend; the result and
        the solver's name."""
        backend = make_backend(self.backend_name)
        return backend.solve(problem), backend.solver_name or backend.name

    def recover(self, failed: QpResult) -> tuple[QpResult | None, ControlStatus, str, str]:
        """After the backend failed this tick: ``(result, status, message, group)``.

        ``result`` is a fresh solution of the full QP (status ``RESOLVED``), or that of the
        QP with the named limit group relaxed (``RELAXED``), or ``None`` (command the safe
        fallback); ``group`` names the infeasible group ('' if none could be named).
        """
        builder = self.builder
        message = f"QP failed: {failed.reason}"
        full = builder.assemble_full()
        builder.reduced = False
        retry, solver = self.fresh_solve(full)
        if retry.found:  # a solver failure, not an infeasible problem
            return (retry, ControlStatus.RESOLVED,
                    message + f"; the problem is feasible: commanded a fresh {solver} solution",
                    "")
        group, relaxed = self.blame(full)
        if group:
            message += f"; infeasible constraint group: {group}"
        if relaxed is None:
            return None, ControlStatus.FALLBACK, message, group
        return (relaxed, ControlStatus.RELAXED,
                message + "; commanded the solution with that group relaxed", group)

    def diagnose(self) -> tuple[str, QpResult | None]:
        """Name the constraint group that makes the current QP infeasible, if one does.

        First solves the full problem with a fresh workspace: a feasible problem names
        nothing, and the result is ``("", None)``; a failed solve of a feasible problem is
        the solver's failure, not a constraint's. Only an infeasible problem is searched
        (:meth:`blame`).
        """
        problem = self.builder.assemble_full()
        self.builder.reduced = False
        if self._search_backend().solve(problem).found:
            return "", None
        return self.blame(problem)

    def blame(self, problem: QpProblem) -> tuple[str, QpResult | None]:
        """For a full ``problem`` known to be infeasible: copies of it are re-solved with one
        group relaxed at a time (off the hot path), limits before physics, and the first
        group whose relaxation makes it solvable is named. Returns the name ('' if none)
        and, when that group is a limit (not physics), the relaxed problem's solution,
        usable as a command."""
        layout = self.builder.layout
        groups = np.array(problem.row_groups)
        forces = slice(layout.force_start, layout.slack_start)
        joints = slice(6, layout.nv)

        def rows(name: str) -> Callable[[QpProblem], None]:
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
            trial.lb[joints], trial.ub[joints] = -INFINITY, INFINITY

        # Limits first: relaxing the physics (dynamics, stance contacts) would make almost
        # any problem feasible by letting the robot fall, which names nothing useful.
        candidates = [("torque limits", rows("torque limits"), True),
                      ("normal force bounds", normal_force, True),
                      ("friction", rows("friction"), True), ("joint limits", joint_limits, True),
                      ("support polygon", rows("support polygon"), True)]
        candidates += [(name, rows(name), True) for name in dict.fromkeys(problem.row_groups)
                       if name and name not in _BUILTIN_GROUPS]
        candidates += [("stance contacts", rows("stance contacts"), False),
                       ("dynamics", rows("dynamics"), False)]
        searcher = self._search_backend()
        for name, relax, usable in candidates:
            trial = problem.copy()
            relax(trial)
            result = searcher.solve(trial)
            if result.found:
                return name, result if usable else None
        return "", None

    def _search_backend(self) -> QpBackend:
        return make_backend(self._searcher)
