"""Stacks registered tasks and constraints into the control tick's QP, one plan per layout."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from tasks.constraint import Constraint, Elimination
from tasks.contact_task import ContactTask
from tasks.task import Task
from tasks.variable_layout import VariableLayout
from wbc.backends.backend import QpBackend
from wbc.backends.qp_problem import QpProblem
from wbc.controller.joint_torques import JointTorques
from wbc.controller.task_stack import TaskStack
from wbc.controller.tick_plan import Regularization, TickPlan
from wbc.core.compiled_program import Step
from wbc.core.errors import ConfigurationError
from wbc.model.kinematics import RobotKinematics

__all__ = ["ProblemBuilder", "Regularization"]


class ProblemBuilder:
    """Builds the tick's QP from registered tasks (costs) and constraints.

    Each task is handed a :class:`tasks.TaskBlock` of the stacked task rows, each constraint
    a :class:`tasks.ConstraintBlock` of the QP, and both write there in place. The variable
    layout follows from what is registered and which contacts carry load
    (:meth:`set_loaded_contacts`); each layout gets one :class:`TickPlan` the first time it
    is used (or :meth:`prepare` makes it): its arrays, its compiled calls bound to them, its
    reduction. Registering or removing anything drops every plan.

    Every tick, :meth:`build` runs the tasks and constraints and stacks them in one compiled
    call (:meth:`evaluate` then :meth:`assemble`): the full QP over ``x = [qdd, forces,
    slacks]``, or, when the constraints declare both :class:`tasks.Elimination` kinds (on the
    builder's contact task) and ``reduce`` is set, the reduced QP (:mod:`.qp_kernel`)."""

    def __init__(self, kinematics: RobotKinematics, contact_task: ContactTask,
                 contacts: Sequence[str], *, leg_columns: np.ndarray | None = None,
                 regularization: Regularization | None = None, reduce: bool = True):
        """Args:
            kinematics: The kinematics the tasks read; updated by the caller each tick.
            contact_task: The contact points, one per name of ``contacts``, in order.
            contacts: The contact names (e.g. the legs) in the order of the contact task.
            leg_columns: For the reduction: the three acceleration columns of the joints
                that move each contact (contacts, 3); ``None`` disables the reduction.
            regularization: The small costs (defaults when ``None``).
            reduce: Whether to solve the reduced QP when possible.
        """
        self.kinematics = kinematics
        self.contact_task = contact_task
        self.contacts = tuple(contacts)
        self.nv = kinematics.nv
        self._regularization = regularization or Regularization()
        self.leg_columns = None if leg_columns is None else np.asarray(leg_columns, np.int64)
        self.reduce = reduce
        self.tasks: list[Task] = []
        self.constraints: list[Constraint] = []
        self._active: dict[Task, bool] = {}
        #: The active tasks (a new tuple whenever the set changes: the tick's program's key).
        self._active_tasks: tuple[Task, ...] = ()
        contact_task.bind(kinematics)
        self._torque_rows = JointTorques(contact_task)
        self._loaded = self.contacts
        self._plans: dict[tuple[str, ...], TickPlan] = {}
        self._current: TickPlan | None = None
        self._last: TickPlan | None = None
        self._stack = TaskStack((), ())
        #: Torques [N m] the torque-rate cost pulls towards (the last command's).
        self.tau_prev = np.zeros(self.nv - 6)
        #: Whether the last :meth:`assemble` produced the reduced QP.
        self.reduced = False
        self._stale = False
        self._after_solve: Callable[[TickPlan], Sequence[Step]] | None = None

    # ------------------------------------------------------------------ registration

    def add_task(self, task: Task, *, active: bool = True) -> Task:
        """Register a task: its rows join the cost from the next tick. Returns it.

        Raises:
            ConfigurationError: Not a task, already registered, sized for another robot, or
                reading frames or variables this builder does not have.
        """
        if not isinstance(task, Task):
            raise ConfigurationError(f"task: expected a tasks.Task, received {type(task).__name__}")
        if task in self._active:
            raise ConfigurationError(f"task: {type(task).__name__} is already registered")
        self._require_frames(task)
        VariableLayout(self.nv, self.contacts, ()).check_variables(
            [v for v in task.variables if not v.startswith("slack:")],
            owner=f"{type(task).__name__}.variables")
        task.bind(self.kinematics)
        self.tasks.append(task)
        self._active[task] = bool(active)
        self._restack()
        return task

    def remove_task(self, task: Task) -> None:
        """Unregister a task (it keeps its values, in arrays of its own)."""
        if task not in self._active:
            raise ConfigurationError(f"task: {type(task).__name__} is not registered")
        self.tasks.remove(task)
        del self._active[task]
        task.detach()
        self._restack()

    def set_active(self, task: Task, active: bool) -> None:
        """Put a registered task in the QP or take it out (kept registered, not updated)."""
        active = bool(active)
        if self._active.get(task) is active:  # registered and already so: nothing changes
            return
        self._active[task] = active
        self._stack.set_active(task, bool(active))
        self._active_tasks = tuple(t for t in self.tasks if self._active[t])

    def add_constraint(self, constraint: Constraint) -> Constraint:
        """Register a constraint: its rows join the QP from the next tick. Returns it."""
        if not isinstance(constraint, Constraint):
            raise ConfigurationError(f"constraint: expected a tasks.Constraint, received "
                                     f"{type(constraint).__name__}")
        self._require_frames(constraint)
        constraint.bind(self.kinematics)
        self.constraints.append(constraint)
        self._drop_plans()
        return constraint

    def remove_constraint(self, constraint: Constraint) -> None:
        """Unregister a constraint."""
        if constraint not in self.constraints:
            raise ConfigurationError(
                f"constraint: {type(constraint).__name__} is not registered")
        self.constraints.remove(constraint)
        self._drop_plans()

    @property
    def regularization(self) -> Regularization:
        """The small costs (read them; change them with :meth:`set_regularization`)."""
        return self._regularization

    def set_regularization(self, regularization: Regularization) -> None:
        """Use these small costs from the next tick (each layout's plan is made again)."""
        self._regularization = Regularization(**vars(regularization))
        self._drop_plans()

    def set_after_solve(self, steps: Callable[[TickPlan], Sequence[Step]] | None) -> None:
        """Steps :meth:`solve`'s compiled call runs once it accepted a solution: ``steps(plan)``
        gives a layout's (kernels and their arguments, e.g. shaping the motor command)."""
        self._after_solve = steps
        for plan in self._plans.values():
            plan.after_solve = steps
            plan.forget_solve()

    def _require_frames(self, item: Task | Constraint) -> None:
        missing = [f for f in item.frames if f not in self.kinematics.frames]
        if missing:
            raise ConfigurationError(
                f"{type(item).__name__}: frames {missing} are not computed by the controller's "
                f"kinematics; available frames: {list(self.kinematics.frames)} (pass the frame "
                f"names when creating the controller: extra_frames=...)")

    def _restack(self) -> None:
        """Stack the tasks' rows anew (each task gets its block) and drop the plans."""
        self._stack = TaskStack(self.tasks, [self._active[t] for t in self.tasks])
        self._active_tasks = tuple(t for t in self.tasks if self._active[t])
        self._drop_plans()

    def _drop_plans(self) -> None:
        self._plans.clear()
        self._current = None
        self._last = None

    @property
    def can_reduce(self) -> bool:
        """Whether the reduced QP can be built: ``reduce`` is set, the legs' columns are
        known, and the registered constraints declare each :class:`tasks.Elimination` once,
        on this builder's contact task."""
        if not self.reduce or self.leg_columns is None:
            return False
        declared = [c for c in self.constraints if c.eliminable_as is not None]
        kinds = [c.eliminable_as for c in declared if c.eliminable_as is not None]
        return (sorted(kinds, key=lambda k: k.value) == sorted(Elimination, key=lambda k: k.value)
                and all(getattr(c, "contacts", None) is self.contact_task for c in declared))

    def _all_constraints(self) -> list[Constraint]:
        """The registered constraints, and rows that give the torques if none does."""
        if any(c.gives_torques for c in self.constraints):
            return list(self.constraints)
        return [*self.constraints, self._torque_rows]

    # ------------------------------------------------------------------ layouts

    def set_loaded_contacts(self, contacts: Sequence[str]) -> None:
        """The contacts that carry load (have force variables and stance rows)."""
        loaded = self._ordered(contacts)
        if loaded != self._loaded:
            self._loaded = loaded
            self._current = None

    def _ordered(self, contacts: Sequence[str]) -> tuple[str, ...]:
        """``contacts`` in the builder's order, each checked to be one of its contacts."""
        unknown = sorted(set(contacts) - set(self.contacts))
        if unknown:
            raise ConfigurationError(f"contacts: unknown contact(s) {unknown}; valid contacts: "
                                     f"{list(self.contacts)}")
        return tuple(c for c in self.contacts if c in set(contacts))

    @property
    def layout(self) -> VariableLayout:
        """The current variable layout."""
        return self._plan().layout

    @property
    def plan(self) -> TickPlan:
        """The current layout's tick plan."""
        return self._plan()

    @property
    def problem(self) -> QpProblem:
        """The full QP of the current layout (over ``x``): its constraints as last updated
        (its cost as last filled by :meth:`assemble_full`)."""
        plan = self._plan()
        self._refresh_eliminated(plan)
        return plan.full

    @property
    def reduced_problem(self) -> QpProblem | None:
        """The reduced QP of the current layout (``None`` when it cannot be reduced)."""
        return self._plan().reduced

    @property
    def solution(self) -> np.ndarray:
        """The last solution ``x`` (zeros before any)."""
        return self._plan().x

    def _plan(self) -> TickPlan:
        current = self._current
        if current is not None:
            return current
        plan = self._plan_of(self._loaded)
        previous = self._last
        if previous is not None and previous is not plan:
            plan.carry_over(previous)
            plan.setup()
        self._current = self._last = plan
        return plan

    def _plan_of(self, loaded: tuple[str, ...]) -> TickPlan:
        """The plan of these loaded contacts, made on first use."""
        plan = self._plans.get(loaded)
        if plan is None:
            constraints = self._all_constraints()
            slacks = tuple(s for c in constraints for s in c.slacks)
            layout = VariableLayout(self.nv, self.contacts, loaded, slacks)
            eliminated = ([c.eliminable_as is not None for c in constraints]
                          if self.can_reduce else None)
            plan = TickPlan(layout, constraints, self._stack, self._regularization,
                            kinematics=self.kinematics, contact_task=self.contact_task,
                            tau_prev=self.tau_prev, eliminated=eliminated,
                            leg_columns=self.leg_columns)
            plan.after_solve = self._after_solve
            self._plans[loaded] = plan
        return plan

    def prepare(self, loaded_sets: Sequence[Sequence[str]], *,
                swing_tasks: Mapping[str, Task] | None = None,
                backend: QpBackend | None = None) -> list[QpProblem]:
        """Get the plans of these sets of loaded contacts ready before they are needed.

        Makes each layout's plan (its arrays, the compiled calls bound to them) and binds
        every registered task's kernel, active or not: a layout's first tick, and a
        kernel's first call in a process, otherwise cost milliseconds, at the moment a foot
        leaves or touches the ground. The current layout and everything the next tick
        computes are left as they were (a task with no target yet binds on its first tick).

        With ``swing_tasks`` (a task for each contact, active exactly while that contact
        is not loaded; the others as they are now), each layout's compiled tick program
        (:meth:`TickPlan.program`) is made too; with ``backend``, its preparation of each
        QP and the compiled solve (:meth:`TickPlan.solve_program`).

        Returns:
            The QPs the tick will solve in these layouts (the reduced ones where the
            reduction applies), for a solver backend to prepare.
        """
        kin = self.kinematics
        for task in self.tasks:
            task.prepare(kin)
        self.contact_task.prepare(kin)
        problems = []
        for contacts in loaded_sets:
            loaded = self._ordered(contacts)
            plan = self._plan_of(loaded)
            problems.append(plan.full if plan.reduced is None else plan.reduced)
            if backend is not None:
                backend.prepare(problems[-1])
                plan.solve_program(backend)
            if swing_tasks is not None:
                swing = {task: contact not in loaded for contact, task in swing_tasks.items()}
                try:
                    plan.program(tuple(t for t in self.tasks if swing.get(t, self._active[t])))
                except ConfigurationError:  # a task without a target: made on first use
                    pass
        return problems

    # ------------------------------------------------------------------ the tick

    def evaluate(self) -> None:
        """Run the contact task, the active tasks and the constraints at the last state (with
        the reduced QP, the eliminated constraints only when :attr:`problem` or
        :meth:`assemble_full` need them)."""
        kin = self.kinematics
        plan = self._plan()
        self.contact_task.evaluate(kin)
        for task in self._active_tasks:
            task.evaluate(kin)
        for call in plan.calls:
            call()
        self._stale = plan.reduction is not None

    def build(self) -> QpProblem:
        """:meth:`evaluate` then :meth:`assemble` in one compiled call (the layout's
        :meth:`TickPlan.program`, Python tasks run in their place): this tick's QP."""
        plan = self._current or self._plan()
        solved = plan.program(self._active_tasks).run()
        reduction = plan.reduction
        self._stale = reduction is not None
        if reduction is not None and solved:
            self.reduced = True
            return reduction.problem
        self.reduced = False
        return self.assemble_full()

    def solve(self, backend: QpBackend) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """After :meth:`build`: the reduced QP solved and accepted in one compiled call
        (:meth:`TickPlan.solve_program`): ``x``, the torques [N m] and the forces (new
        arrays); ``None`` without one or when it fails (then solve and :meth:`accept`)."""
        plan = self._current
        program = plan.solve_program(backend) if self.reduced and plan is not None else None
        if plan is None or program is None or not program.run():
            if plan is not None and program is not None:
                plan.forget_solve()  # the failure path sets the backend up anew
            return None
        return plan.x, plan.tau.copy(), plan.forces.copy()

    def _refresh_eliminated(self, plan: TickPlan) -> None:
        if self._stale:
            for call in plan.eliminated_calls:
                call()
            self._stale = False

    def assemble(self) -> QpProblem:
        """The QP to solve this tick: the reduced one when possible, else the full one."""
        plan = self._plan()
        reduction = plan.reduction
        if reduction is not None and reduction.call():
            self.reduced = True
            return reduction.problem
        self.reduced = False
        return self.assemble_full()

    def assemble_full(self) -> QpProblem:
        """Fill the full QP's cost (its constraints are always up to date)."""
        plan = self._plan()
        self._refresh_eliminated(plan)
        p = plan.full
        p.H[:] = 0.0
        p.f[:] = 0.0
        for call in plan.full_cost:
            call()
        return p

    def accept(self, solution: np.ndarray,
               forces: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Record the solver's solution of the problem :meth:`assemble` returned.

        Returns ``x`` and the joint torques [N m] it implies (a new array); fills
        ``forces`` (contacts, 3) [N] when given, zeros for the contacts without force
        variables.
        """
        return self._plan().accept(solution, forces, reduced=self.reduced)

    def torques(self) -> np.ndarray:
        """Joint torques [N m] of the last accepted solution: ``tau = A_tau x + h_a``."""
        return self._plan().torques()

    def reset_rates(self, x: np.ndarray | None = None) -> None:
        """Set the previous solution the rate costs pull towards (zeros when ``None``)."""
        plan = self._plan()
        plan.x_prev[:] = 0.0 if x is None else x
