"""One variable layout's tick, planned once: its QP, the constraints' blocks, the task costs'
columns, the reduction, and every compiled call bound to them."""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from tasks.constraint import Constraint, ConstraintBlock
from tasks.contact_task import ContactTask
from tasks.task import Task
from tasks.variable_layout import VariableLayout
from wbc.backends.backend import QpBackend
from wbc.backends.qp_problem import QpProblem
from wbc.controller import cost_kernels, qp_kernel
from wbc.controller.task_stack import TaskStack
from wbc.core.compiled_call import bind_compiled
from wbc.core.compiled_program import CompiledProgram, Guard, Step
from wbc.model.kinematics import RobotKinematics


@dataclass
class Regularization:
    """Small costs that make the QP strictly convex and the solution smooth in time.

    Attributes:
        acceleration: Weight of ``|qdd|^2``. force: of ``|f|^2``.
        acceleration_rate, force_rate: Weights of the change from the previous solution.
        torque_rate: Weight of ``|tau - tau_prev|^2`` (the torques the previous tick sent).
        slack: Weight of each slack variable, by name (0 when not listed).
    """

    acceleration: float = 1e-4
    force: float = 1e-5
    acceleration_rate: float = 0.0
    force_rate: float = 0.0
    torque_rate: float = 0.0
    slack: dict[str, float] | None = None


class Reduction:
    """The reduced QP of a layout and its map ``x = T z + t0`` (:mod:`qp_kernel`), with the
    reduction kernel bound to every array it reads and writes."""

    def __init__(self, plan: TickPlan, constraints: Sequence[Constraint],
                 eliminated: Sequence[bool], leg_columns: np.ndarray,
                 kinematics: RobotKinematics, contact_task: ContactTask,
                 regularization: Regularization, tau_prev: np.ndarray, tau_index: int):
        layout, nv, full = plan.layout, plan.layout.nv, plan.full
        stance_columns = {int(c) for i in layout.loaded for c in leg_columns[i]}
        self.free_columns = np.array([c for c in range(6, nv) if c not in stance_columns],
                                     dtype=np.int64)
        nz = self.free_columns.size + layout.n - layout.force_start
        self.T = np.zeros((layout.n, nz))
        self.t0 = np.zeros(layout.n)
        z_of_x = np.full(layout.n, -1, dtype=np.int64)
        z_of_x[self.free_columns] = np.arange(self.free_columns.size)
        z_of_x[layout.force_start:] = np.arange(self.free_columns.size, nz)
        #: Stance joints' accelerations: their bounds become rows of the reduced QP.
        bounded = np.array(sorted(stance_columns), dtype=np.int64)
        kept = [r for block, gone in zip(plan.blocks, eliminated) if not gone
                for r in range(block.rows.start, block.rows.stop)]
        kept_rows = np.array(kept, dtype=np.int64)
        self.problem = p = QpProblem(nz, kept_rows.size + bounded.size)
        p.is_equality[:kept_rows.size] = full.is_equality[kept_rows]
        p.row_groups[:kept_rows.size] = [full.row_groups[r] for r in kept]
        p.row_groups[kept_rows.size:] = ["joint limits"] * bounded.size
        #: The first torque row among the reduced rows.
        self.tau_first = int(np.searchsorted(kept_rows, plan.blocks[tau_index].rows.start))
        self.tau_offset = np.zeros(nv - 6)
        k = len(layout.loaded)
        #: The reduction kernel's arguments (a step of the tick's compiled program).
        self.arguments = (
            qp_kernel.Dynamics(kinematics.mass_matrix, kinematics.nonlinear_effects),
            qp_kernel.ContactRows(contact_task.jacobian, contact_task.drift,
                                  contact_task.desired_acceleration, layout.loaded,
                                  leg_columns, self.free_columns, layout.force_start),
            qp_kernel.FullRows(full.A, full.lower, full.upper, full.lb, full.ub, kept_rows,
                               z_of_x, bounded),
            plan.task_rows,
            qp_kernel.Costs(plan.weights, plan.rate_weights, plan.x_prev, tau_prev,
                            float(regularization.torque_rate), self.tau_first),
            qp_kernel.ReducedRows(self.T, self.t0, p.H, p.f, p.A, p.lower, p.upper, p.lb, p.ub,
                                  np.zeros(p.m), np.zeros(contact_task.dim), self.tau_offset),
            qp_kernel.Work(np.zeros((k, 3, 3)), np.zeros((k, 3, 3)), np.zeros((6, 6)),
                           np.zeros((6, nz + 1)), np.zeros(nz)))
        #: Writes this tick's reduced QP; False when a leg is singular (solve the full QP).
        self.call: Callable[[], bool] = bind_compiled(qp_kernel.reduced_problem,
                                                      *self.arguments)



class TickPlan:
    """Everything one variable layout needs every tick, allocated and bound once.

    The full QP over ``x`` with each constraint's :class:`tasks.ConstraintBlock` in it;
    the constraints' tick calls (:meth:`tasks.Constraint.tick_call`); the columns of ``x``
    each task's Jacobian spans here; the regularisation; the previous solution; and, when
    the registered constraints allow it, the :class:`Reduction`. A problem builder keeps
    one plan per layout and drops them all when what is registered changes.
    """

    def __init__(self, layout: VariableLayout, constraints: Sequence[Constraint],
                 stack: TaskStack, regularization: Regularization, *,
                 kinematics: RobotKinematics, contact_task: ContactTask,
                 tau_prev: np.ndarray, eliminated: Sequence[bool] | None,
                 leg_columns: np.ndarray | None):
        """Args:
            layout: The variables.
            constraints: The registered constraints (one of them ``gives_torques``).
            stack: The registered tasks' rows.
            regularization: The small costs.
            kinematics, contact_task: What the reduction reads.
            tau_prev: The torques the torque-rate term pulls towards (read in place).
            eliminated: Which constraints the reduction eliminates; ``None``: no reduction.
            leg_columns: The three acceleration columns moving each contact (reduction).
        """
        self.layout = layout
        self.constraints = tuple(constraints)
        n = layout.n
        counts = [c.rows(layout) for c in constraints]
        self.full = full = QpProblem(n, int(sum(counts)))
        self.blocks: list[ConstraintBlock] = []
        start = 0
        for constraint, count in zip(constraints, counts):
            rows = slice(start, start + count)
            self.blocks.append(ConstraintBlock(A=full.A[rows], lower=full.lower[rows],
                                               upper=full.upper[rows], lb=full.lb, ub=full.ub,
                                               rows=rows))
            full.is_equality[rows] = constraint.equality
            full.row_groups[rows] = [constraint.name] * count
            start += count
        self.tau_index = next(i for i, c in enumerate(constraints) if c.gives_torques)
        self.tau_block = self.blocks[self.tau_index]
        self.identity, self.zero = np.eye(n), np.zeros(n)
        self.x, self.x_prev = np.zeros(n), np.zeros(n)
        nv, nf = layout.nv, 3 * len(layout.force_contacts)
        reg = regularization
        self.weights, self.rate_weights = np.zeros(n), np.zeros(n)
        self.weights[:nv] = reg.acceleration + reg.acceleration_rate
        self.rate_weights[:nv] = reg.acceleration_rate
        self.weights[nv:nv + nf] = reg.force + reg.force_rate
        self.rate_weights[nv:nv + nf] = reg.force_rate
        for name in layout.slacks:
            self.weights[layout.slack_column(name)] = (reg.slack or {}).get(name, 0.0)
        self.g = np.zeros(n)
        #: The stacked task rows with this layout's columns, as the cost kernels take them.
        self.task_rows = stack.rows(stack.columns(layout))
        self.reduction: Reduction | None = None
        if eliminated is not None and leg_columns is not None:
            self.reduction = Reduction(self, constraints, eliminated, leg_columns, kinematics,
                                       contact_task, regularization, tau_prev, self.tau_index)
        #: The full QP's cost terms, bound to its arrays: the tasks, the regularisation, the
        #: torque-rate term, then the lower triangle (after ``H`` and ``f`` are zeroed).
        full_cost = [
            bind_compiled(cost_kernels.accumulate_tasks, self.task_rows, self.identity,
                          self.zero, full.H, full.f, self.g),
            bind_compiled(cost_kernels.add_diagonal_cost, self.weights, self.rate_weights,
                          self.x_prev, self.identity, self.zero, full.H, full.f)]
        if regularization.torque_rate > 0.0:
            full_cost.append(bind_compiled(
                cost_kernels.add_row_least_squares, self.tau_block.A,
                kinematics.nonlinear_effects[6:], tau_prev, float(regularization.torque_rate),
                full.H, full.f))
        full_cost.append(bind_compiled(cost_kernels.mirror_upper, full.H))
        self.full_cost: list[Callable[[], None]] = full_cost
        gone: Sequence[bool] = (eliminated if self.reduction is not None and eliminated is not None
                                else [False] * len(constraints))
        self.setup()
        self._kinematics, self._contact_task, self._gone = kinematics, contact_task, gone
        self._programs: dict[tuple[Task, ...], CompiledProgram] = {}
        self._last_program: tuple[tuple[Task, ...] | None, CompiledProgram | None] = (None, None)
        self._tau_prev = tau_prev
        #: The force columns carried over from each layout switched from (:meth:`carry_over`).
        self._carried: dict[VariableLayout, list[tuple[slice, slice]]] = {}
        #: The torques [N m] and forces (contacts, 3) [N] of the last solve in compiled code.
        self.tau, self.forces = np.zeros(nv - 6), np.zeros((len(layout.contacts), 3))
        self._solve: tuple[QpBackend | None, CompiledProgram | None, int] = (None, None, -1)
        #: Steps the compiled solve runs after accepting a solution, made from this plan
        #: (:meth:`ProblemBuilder.set_after_solve`); ``None``: none.
        self.after_solve: Callable[[TickPlan], Sequence[Step]] | None = None
        calls = [(c.tick_call(kinematics, layout, b), g)
                 for c, b, g in zip(constraints, self.blocks, gone)]
        #: The constraints' tick calls, without those the reduction eliminates.
        self.calls: list[Callable[[], None]] = [call for call, g in calls if not g]
        #: The eliminated constraints' tick calls: run for the full QP only.
        self.eliminated_calls: list[Callable[[], None]] = [call for call, g in calls if g]

    def program(self, tasks: tuple[Task, ...]) -> CompiledProgram:
        """The tick's work with these tasks active, as one compiled call where every step
        has a kernel (:class:`wbc.core.compiled_program.CompiledProgram`): the contact task,
        the tasks, the constraints the reduction keeps, then the reduction (the program
        returns what it does). Made once for each set of active tasks.
        """
        last = self._last_program
        if last[0] is tasks and last[1] is not None:  # the tick's case: the last tick's tuple
            return last[1]
        program = self._programs.get(tasks)
        if program is None:
            kinematics, layout = self._kinematics, self.layout
            steps = [_task_step(task, kinematics) for task in (self._contact_task, *tasks)]
            steps += [_constraint_step(c, kinematics, layout, b)
                      for c, b, gone in zip(self.constraints, self.blocks, self._gone)
                      if not gone]
            if self.reduction is not None:
                steps.append((qp_kernel.reduced_problem, self.reduction.arguments))
            program = self._programs[tasks] = CompiledProgram(steps)
        self._last_program = (tasks, program)
        return program

    @property
    def last_program(self) -> CompiledProgram | None:
        """The program the last :meth:`program` call gave (the last tick's)."""
        return self._last_program[1]

    def solve_program(self, backend: QpBackend) -> CompiledProgram | None:
        """The reduced QP solved by ``backend``'s compiled solve
        (:meth:`wbc.backends.backend.QpBackend.compiled_solve`) and, when it finds a
        solution, accepted (``x``, ``x_prev``, :attr:`tau`, :attr:`forces`, the torque-rate
        cost's torques), in one compiled call that returns whether it found one; ``None``
        without a reduction or a compiled solve. Kept while the backend and the reduced QP's
        structure are the same."""
        reduction = self.reduction
        if reduction is None:
            return None
        held, program, version = self._solve
        problem = reduction.problem
        if held is backend and version == problem.structure_version:
            return program
        program, compiled = None, backend.compiled_solve(problem)
        if compiled is not None:
            kernel, arguments, z = compiled
            layout, r = self.layout, reduction
            after = () if self.after_solve is None else tuple(self.after_solve(self))
            program = CompiledProgram([Guard(kernel, arguments), (qp_kernel.accept, (
                r.T, r.t0, z, self.x, self.x_prev, problem.A, r.tau_first, r.tau_offset,
                self.tau, layout.loaded, layout.force_start, self.forces, self._tau_prev)),
                *after])
        self._solve = (backend, program, problem.structure_version)
        return program

    def accept(self, solution: np.ndarray, forces: np.ndarray | None, *,
               reduced: bool) -> tuple[np.ndarray, np.ndarray]:
        """Record a solver's solution of the reduced QP (``reduced``) or of the full one:
        ``x`` and the joint torques [N m] it implies (a new array); fills ``forces``
        (contacts, 3) [N] (a new array when ``None``), zeros for contacts without forces."""
        layout, reduction = self.layout, self.reduction
        tau = np.empty(layout.nv - 6)
        if forces is None:
            forces = np.empty((len(layout.contacts), 3))
        if reduced and reduction is not None:
            qp_kernel.finish(reduction.T, reduction.t0, solution, self.x, self.x_prev,
                             reduction.problem.A, reduction.tau_first, reduction.tau_offset,
                             tau, layout.loaded, layout.force_start, forces)
        else:
            self.x[:] = solution
            self.x_prev[:] = self.x
            tau[:] = self.torques()
            forces[:] = 0.0
            forces[layout.loaded] = self.x[layout.force_start:layout.slack_start].reshape(-1, 3)
        return self.x, tau

    def torques(self) -> np.ndarray:
        """Joint torques [N m] of the last accepted solution: ``tau = A_tau x + h_a``."""
        return self.tau_block.A @ self.x + self._kinematics.nonlinear_effects[6:]

    def forget_solve(self) -> None:
        """Ask the backend for its compiled solve again (after it was set up anew)."""
        self._solve = (None, None, -1)

    @property
    def reduced(self) -> QpProblem | None:
        """The reduced QP (``None`` when this layout has no reduction)."""
        return None if self.reduction is None else self.reduction.problem

    def setup(self) -> None:
        """The constraints' constant entries (:meth:`tasks.Constraint.setup`)."""
        for constraint, block in zip(self.constraints, self.blocks):
            constraint.setup(self.layout, block)

    def carry_over(self, previous: TickPlan) -> None:
        """Start from the previous layout's solution: accelerations, and the forces of the
        contacts loaded in both."""
        nv = self.layout.nv
        self.x_prev[:] = 0.0
        self.x_prev[:nv] = previous.x_prev[:nv]
        self.x[:] = 0.0
        pairs = self._carried.get(previous.layout)
        if pairs is None:  # once per previous layout: a trot switches four times a second
            pairs = self._carried[previous.layout] = [
                (new, old) for old, new in (
                    (previous.layout.force_slice(contact), self.layout.force_slice(contact))
                    for contact in self.layout.force_contacts)
                if old is not None and new is not None]
        for new, old in pairs:
            self.x_prev[new] = previous.x_prev[old]


def _task_step(task: Task, kinematics: RobotKinematics) -> Step:
    """A task's kernel and arguments, or (a task written in Python) its evaluation."""
    if kinematics is not task._kinematics:
        task.bind(kinematics)
    compiled = task._compiled_call(kinematics)
    return functools.partial(task.evaluate, kinematics) if compiled is None else compiled


def _constraint_step(constraint: Constraint, kinematics: RobotKinematics,
                     layout: VariableLayout, block: ConstraintBlock) -> Step:
    """A constraint's kernel and arguments, or its :meth:`tasks.Constraint.tick_call`."""
    if type(constraint).write is Constraint.write:
        compiled = constraint._compiled_call(kinematics, layout, block)
        if compiled is not None:
            return compiled
    return constraint.tick_call(kinematics, layout, block)
