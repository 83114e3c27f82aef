"""Stacks registered tasks and constraints into the control tick's QP, in blocks allocated once."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from tasks.constraint import Constraint, ConstraintBlock
from tasks.contact_task import ContactTask
from tasks.floating_base_dynamics import FloatingBaseDynamics
from tasks.stance_contacts import StanceContacts
from tasks.task import Task
from tasks.torque_limits import TorqueLimits
from tasks.variable_layout import VariableLayout
from wbc.backends.qp_problem import QpProblem
from wbc.controller import qp_kernel
from wbc.core.compiled_call import bind_compiled
from wbc.core.errors import ConfigurationError

if TYPE_CHECKING:
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


#: The constraints the reduced QP eliminates (they define the map ``x = T z + t0``).
_ELIMINATED = (FloatingBaseDynamics, StanceContacts)


class _LayoutProblem:
    """Everything one variable layout needs, allocated once: the full QP, each constraint's
    block, and the reduced QP with its map ``x = T z + t0``."""

    def __init__(self, layout: VariableLayout, constraints: Sequence[Constraint],
                 regularization: Regularization, leg_columns: np.ndarray | None):
        self.layout = layout
        n = layout.n
        counts = [c.rows(layout) for c in constraints]
        m = int(sum(counts))
        self.full = QpProblem(n, m)
        self.blocks: list[ConstraintBlock] = []
        start = 0
        for constraint, count in zip(constraints, counts):
            rows = slice(start, start + count)
            p = self.full
            self.blocks.append(ConstraintBlock(A=p.A[rows], lower=p.lower[rows],
                                               upper=p.upper[rows], lb=p.lb, ub=p.ub, rows=rows))
            p.is_equality[rows] = constraint.equality
            p.row_groups[rows] = [constraint.name] * count
            start += count
        self.identity = np.eye(n)
        self.zero = np.zeros(n)
        self.x = np.zeros(n)
        self.x_prev = np.zeros(n)
        nv = layout.nv
        nf = 3 * len(layout.force_contacts)
        reg = regularization
        self.weights = np.zeros(n)
        self.rate_weights = np.zeros(n)
        self.weights[:nv] = reg.acceleration + reg.acceleration_rate
        self.rate_weights[:nv] = reg.acceleration_rate
        self.weights[nv:nv + nf] = reg.force + reg.force_rate
        self.rate_weights[nv:nv + nf] = reg.force_rate
        for name in layout.slacks:
            self.weights[layout.slack_column(name)] = (reg.slack or {}).get(name, 0.0)
        self.scratch = np.zeros(n)
        self.g = np.zeros(n)
        self.tau_block: ConstraintBlock | None = None
        self.reduced: QpProblem | None = None
        #: The reduction kernel bound to its arguments, and what they were gathered for.
        self.reduce_call: Callable[[], bool] | None = None
        self.reduce_key: tuple | None = None
        if leg_columns is not None:
            self._allocate_reduction(constraints, leg_columns)
        #: The constraints written every tick (with the reduction, not the eliminated ones).
        self.per_tick = [(c, b) for c, b in zip(constraints, self.blocks)
                         if self.reduced is None or not isinstance(c, _ELIMINATED)]
        #: Their tick calls (:meth:`tasks.Constraint.tick_call`), bound once for this layout.
        self.calls: list[Callable[[], None]] | None = None

    def _allocate_reduction(self, constraints: Sequence[Constraint],
                            leg_columns: np.ndarray) -> None:
        layout, nv = self.layout, self.layout.nv
        stance_columns = {int(c) for i in layout.loaded for c in leg_columns[i]}
        self.free_columns = np.array([c for c in range(6, nv) if c not in stance_columns],
                                     dtype=np.int64)
        nz = self.free_columns.size + layout.n - layout.force_start
        self.T = np.zeros((layout.n, nz))
        self.t0 = np.zeros(layout.n)
        self.z_of_x = np.full(layout.n, -1, dtype=np.int64)
        self.z_of_x[self.free_columns] = np.arange(self.free_columns.size)
        self.z_of_x[layout.force_start:] = np.arange(self.free_columns.size, nz)
        #: Stance joints' accelerations: their bounds become rows of the reduced QP.
        self.bounded = np.array(sorted(stance_columns), dtype=np.int64)
        kept = [r for c, b in zip(constraints, self.blocks) if not isinstance(c, _ELIMINATED)
                for r in range(b.rows.start, b.rows.stop)]
        self.kept_rows = np.array(kept, dtype=np.int64)
        m_r = self.kept_rows.size + self.bounded.size
        self.reduced = QpProblem(nz, m_r)
        p = self.reduced
        p.is_equality[:self.kept_rows.size] = self.full.is_equality[self.kept_rows]
        p.row_groups[:self.kept_rows.size] = [self.full.row_groups[r] for r in kept]
        p.row_groups[self.kept_rows.size:] = ["joint limits"] * self.bounded.size
        self.offset = np.zeros(m_r)
        self.rhs = np.zeros(3 * len(layout.contacts))
        self.tau_offset = np.zeros(nv - 6)
        #: First torque-limit row among the reduced rows (-1: no torque limits registered).
        self.tau_first = -1
        for constraint, block in zip(constraints, self.blocks):
            if isinstance(constraint, TorqueLimits):
                self.tau_first = int(np.searchsorted(self.kept_rows, block.rows.start))
        k = len(layout.loaded)
        self.work = (np.zeros((k, 3, 3)), np.zeros((k, 3, 3)), np.zeros((6, 6)),
                     np.zeros((6, nz + 1)))


class ProblemBuilder:
    """Builds the tick's QP from registered tasks (costs on ``qdd``) and constraints.

    The variable layout follows from what is registered and which contacts carry load
    (:meth:`set_loaded_contacts`); each layout's arrays are allocated the first time it is
    used and kept. Every tick, :meth:`update` runs the tasks and constraints (each writes its
    own block in place) and :meth:`assemble` stacks them: into the full QP over
    ``x = [qdd, forces, slacks]``, or, when a :class:`FloatingBaseDynamics` and a
    :class:`StanceContacts` are registered and ``reduce`` is set, into the reduced QP over
    the free variables (see :mod:`wbc.controller.qp_kernel`), which has the same solution.
    """

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
        self.regularization = regularization or Regularization()
        self.leg_columns = None if leg_columns is None else np.asarray(leg_columns, np.int64)
        self.reduce = reduce
        self.tasks: list[Task] = []
        self.constraints: list[Constraint] = []
        contact_task.bind(kinematics)
        self._loaded = self.contacts
        self._layouts: dict[tuple, _LayoutProblem] = {}
        self._current: _LayoutProblem | None = None
        self._last: _LayoutProblem | None = None
        self._stack_tasks()
        #: Torques [N m] the torque-rate cost pulls towards (the last command's).
        self.tau_prev = np.zeros(self.nv - 6)
        #: Whether the last :meth:`assemble` produced the reduced QP.
        self.reduced = False
        self._stale = False

    # ------------------------------------------------------------------ registration

    def add_task(self, task: Task, *, active: bool = True) -> Task:
        """Register a task: its rows join the cost from the next tick. Returns it."""
        if not isinstance(task, Task):
            raise ConfigurationError(f"task: expected a tasks.Task, received {type(task).__name__}")
        if task in self.tasks:
            raise ConfigurationError(f"task: {type(task).__name__} is already registered")
        if task.nv != self.nv:
            raise ConfigurationError(f"task: {type(task).__name__} has nv={task.nv}, the robot "
                                     f"has nv={self.nv}")
        self._require_frames(task)
        task.bind(self.kinematics)
        self.tasks.append(task)
        self._stack_tasks()
        self.set_active(task, active)
        return task

    def remove_task(self, task: Task) -> None:
        """Unregister a task."""
        if task not in self.tasks:
            raise ConfigurationError(f"task: {type(task).__name__} is not registered")
        self.tasks.remove(task)
        self._stack_tasks()

    def set_active(self, task: Task, active: bool) -> None:
        """Put a registered task in the QP or take it out (kept registered, not updated)."""
        self._active[self.tasks.index(task)] = bool(active)
        self._active_tasks = [t for t, on in zip(self.tasks, self._active) if on]

    def add_constraint(self, constraint: Constraint) -> Constraint:
        """Register a constraint: its rows join the QP from the next tick. Returns it."""
        if not isinstance(constraint, Constraint):
            raise ConfigurationError(f"constraint: expected a tasks.Constraint, received "
                                     f"{type(constraint).__name__}")
        self._require_frames(constraint)
        constraint.bind(self.kinematics)
        self.constraints.append(constraint)
        self._layouts.clear()
        self._current = None
        return constraint

    def remove_constraint(self, constraint: Constraint) -> None:
        """Unregister a constraint."""
        self.constraints.remove(constraint)
        self._layouts.clear()
        self._current = None

    def _require_frames(self, item: Task | Constraint) -> None:
        missing = [f for f in item.frames if f not in self.kinematics.frames]
        if missing:
            raise ConfigurationError(
                f"{type(item).__name__}: frames {missing} are not computed by the controller's "
                f"kinematics; available frames: {list(self.kinematics.frames)} (pass the frame "
                f"names when creating the controller: extra_frames=...)")

    def _stack_tasks(self) -> None:
        """Re-allocate the stacked task rows and point every task's arrays into them."""
        self._stacking = getattr(self, "_stacking", 0) + 1
        dims = [t.dim for t in self.tasks]
        rows = int(sum(dims))
        self._J = np.zeros((rows, self.nv))
        self._drift = np.zeros(rows)
        self._desired = np.zeros(rows)
        self._row_weights = np.zeros(rows)
        self._row_task = np.repeat(np.arange(len(self.tasks)), dims).astype(np.int64)
        self._gains = np.zeros((len(self.tasks), 3))
        old = getattr(self, "_active", np.ones(0, dtype=bool))
        self._active = np.ones(len(self.tasks), dtype=np.bool_)
        start = 0
        for i, (task, dim) in enumerate(zip(self.tasks, dims)):
            view = slice(start, start + dim)
            for name, stacked in (("jacobian", self._J), ("drift", self._drift),
                                  ("desired_acceleration", self._desired),
                                  ("row_weights", self._row_weights)):
                stacked[view] = getattr(task, name)
                setattr(task, name, stacked[view])
            self._gains[i] = task.gains
            task.gains = self._gains[i]
            task._call = None  # its compiled call held the arrays it had before
            self._active[i] = old[i] if i < old.size else True
            start += dim
        self._active_tasks = [t for t, on in zip(self.tasks, self._active) if on]

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
        return self._problem().layout

    @property
    def problem(self) -> QpProblem:
        """The full QP of the current layout (over ``x``): its constraints as last updated
        (its cost as last filled by :meth:`assemble_full`)."""
        entry = self._problem()
        self._refresh_eliminated(entry)
        return entry.full

    @property
    def reduced_problem(self) -> QpProblem | None:
        """The reduced QP of the current layout (``None`` when it cannot be reduced)."""
        return self._problem().reduced

    @property
    def solution(self) -> np.ndarray:
        """The last solution ``x`` (zeros before any)."""
        return self._problem().x

    def _problem(self) -> _LayoutProblem:
        current = self._current
        if current is not None:
            return current
        entry = self._entry(self._loaded)
        previous = self._last
        if previous is not None and previous is not entry:
            _carry_over(previous, entry)
        for constraint, block in zip(self.constraints, entry.blocks):
            constraint.setup(entry.layout, block)
        self._current = entry
        self._last = entry
        return entry

    def _entry(self, loaded: tuple[str, ...]) -> _LayoutProblem:
        """The layout of these loaded contacts, allocated on first use."""
        slacks = tuple(s for c in self.constraints for s in c.slacks)
        key = (loaded, slacks)
        entry = self._layouts.get(key)
        if entry is None:
            layout = VariableLayout(self.nv, self.contacts, loaded, slacks)
            reducible = (self.reduce and self.leg_columns is not None
                         and sum(isinstance(c, FloatingBaseDynamics)
                                 for c in self.constraints) == 1
                         and sum(isinstance(c, StanceContacts) for c in self.constraints) == 1)
            entry = _LayoutProblem(layout, self.constraints, self.regularization,
                                   self.leg_columns if reducible else None)
            for constraint, block in zip(self.constraints, entry.blocks):
                if isinstance(constraint, TorqueLimits):
                    entry.tau_block = block
            self._layouts[key] = entry
        return entry

    def prepare(self, loaded_sets: Sequence[Sequence[str]]) -> list[QpProblem]:
        """Get the layouts of these sets of loaded contacts ready before they are needed.

        Allocates each layout's arrays and binds its compiled calls (the constraints', the
        reduction's, and every registered task's, active or not): a layout's first tick,
        and a kernel's first call in a process (read from numba's cache), otherwise cost
        milliseconds, at the moment a foot leaves or touches the ground. The current layout
        and everything the next tick computes are left as they were. A task that cannot run
        yet (no target) is left to bind on its first tick.

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
            entry = self._entry(self._ordered(contacts))
            self._bind_calls(entry)
            if entry.reduced is not None:
                self._bind_reduction(entry)
                problems.append(entry.reduced)
            else:
                problems.append(entry.full)
        return problems

    def _bind_calls(self, entry: _LayoutProblem) -> list[Callable[[], None]]:
        if entry.calls is None:
            entry.calls = [constraint.tick_call(self.kinematics, entry.layout, block)
                           for constraint, block in entry.per_tick]
        return entry.calls

    # ------------------------------------------------------------------ the tick

    def update(self) -> None:
        """Run the contact task, the active tasks and the constraints at the last state.

        When the reduced QP can be used, the eliminated constraints (floating-base dynamics,
        stance contacts) are not written: :attr:`problem` and :meth:`assemble_full` write
        them on demand.
        """
        kin = self.kinematics
        entry = self._problem()
        calls = entry.calls if entry.calls is not None else self._bind_calls(entry)
        self.contact_task.update(kin)
        for task in self._active_tasks:
            task.update(kin)
        for call in calls:
            call()
        self._stale = entry.reduced is not None

    def _refresh_eliminated(self, entry: _LayoutProblem) -> None:
        if self._stale:
            for constraint, block in zip(self.constraints, entry.blocks):
                if isinstance(constraint, _ELIMINATED):
                    constraint.update(self.kinematics, entry.layout, block)
            self._stale = False

    def assemble(self) -> QpProblem:
        """The QP to solve this tick: the reduced one when possible, else the full one."""
        entry = self._problem()
        if entry.reduced is not None and self._reduce(entry):
            self.reduced = True
            return entry.reduced
        self.reduced = False
        self.assemble_full()
        return entry.full

    def assemble_full(self) -> QpProblem:
        """Fill the full QP's cost (its constraints are always up to date)."""
        entry = self._problem()
        self._refresh_eliminated(entry)
        p = entry.full
        p.H[:] = 0.0
        p.f[:] = 0.0
        self._costs(entry, entry.identity, entry.zero, p.H, p.f)
        tau = entry.tau_block
        if tau is not None and self.regularization.torque_rate > 0.0:
            offset = self.kinematics.nonlinear_effects[6:]
            qp_kernel.add_row_least_squares(tau.A, offset, self.tau_prev,
                                            self.regularization.torque_rate, p.H, p.f)
        qp_kernel.mirror_upper(p.H)
        return p

    def _costs(self, entry: _LayoutProblem, T: np.ndarray, t0: np.ndarray, H: np.ndarray,
               f: np.ndarray) -> None:
        qp_kernel.accumulate_tasks(self._J, self._drift, self._desired, self._row_weights,
                                   self._row_task, self._gains, self._active, T, t0, H, f,
                                   entry.g)
        qp_kernel.add_diagonal_cost(entry.weights, entry.rate_weights, entry.x_prev, T, t0, H, f)

    def _reduce(self, entry: _LayoutProblem) -> bool:
        # The kernel's 47 arguments are gathered once per layout, task stacking and torque
        # rate weight: every other one is an array updated in place or fixed with the layout.
        return self._bind_reduction(entry)()

    def _bind_reduction(self, entry: _LayoutProblem) -> Callable[[], bool]:
        key = (self._stacking, self.regularization.torque_rate)
        if entry.reduce_key != key:
            entry.reduce_call = bind_compiled(qp_kernel.reduced_problem,
                                              *self._reduce_arguments(entry))
            entry.reduce_key = key
        return entry.reduce_call

    def _reduce_arguments(self, entry: _LayoutProblem) -> tuple:
        kin, task, layout, p, full = (self.kinematics, self.contact_task, entry.layout,
                                      entry.reduced, entry.full)
        L, Linv, K, X = entry.work
        return (
            kin.mass_matrix, kin.nonlinear_effects, task.jacobian, task.drift,
            task.desired_acceleration, layout.loaded, self.leg_columns, entry.free_columns,
            layout.force_start, full.A, full.lower, full.upper, full.lb, full.ub,
            entry.kept_rows, entry.z_of_x, entry.bounded, self._J, self._drift, self._desired,
            self._row_weights, self._row_task, self._gains, self._active, entry.weights,
            entry.rate_weights, entry.x_prev, entry.tau_first, self.tau_prev,
            self.regularization.torque_rate, entry.T, entry.t0, p.H, p.f, p.A, p.lower, p.upper,
            p.lb, p.ub, entry.offset, entry.rhs, entry.tau_offset, L, Linv, K, X, entry.g)

    def accept(self, solution: np.ndarray,
               forces: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Record the solver's solution of the problem :meth:`assemble` returned.

        Returns ``x`` and the joint torques [N m] it implies (a new array); fills
        ``forces`` (contacts, 3) [N] when given, zeros for the contacts without force
        variables.
        """
        entry = self._problem()
        layout = entry.layout
        tau = np.empty(self.nv - 6)
        if forces is None:
            forces = np.empty((len(self.contacts), 3))
        if self.reduced and entry.tau_first >= 0:
            qp_kernel.finish(entry.T, entry.t0, solution, entry.x, entry.x_prev,
                             entry.reduced.A, entry.tau_first, entry.tau_offset, tau,
                             layout.loaded, layout.force_start, forces)
        else:
            if self.reduced:
                qp_kernel.expand(entry.T, entry.t0, solution, entry.x)
            else:
                entry.x[:] = solution
            entry.x_prev[:] = entry.x
            tau[:] = self.torques()
            forces[:] = 0.0
            forces[layout.loaded] = entry.x[layout.force_start:layout.slack_start].reshape(-1, 3)
        return entry.x, tau

    def torques(self) -> np.ndarray:
        """Joint torques [N m] of the last accepted solution: ``tau = A_tau x + h_a``."""
        entry = self._problem()
        return entry.tau_block.A @ entry.x + self.kinematics.nonlinear_effects[6:]

    def reset_rates(self, x: np.ndarray | None = None) -> None:
        """Set the previous solution the rate costs pull towards (zeros when ``None``)."""
        entry = self._problem()
        entry.x_prev[:] = 0.0 if x is None else x


def _carry_over(previous: _LayoutProblem, entry: _LayoutProblem) -> None:
    """Carry the previous solution into a new layout: accelerations, and the forces of the
    contacts loaded in both."""
    nv = entry.layout.nv
    entry.x_prev[:] = 0.0
    entry.x_prev[:nv] = previous.x_prev[:nv]
    entry.x[:] = 0.0
    for contact in entry.layout.force_contacts:
        old, new = previous.layout.force_slice(contact), entry.layout.force_slice(contact)
        if old is not None and new is not None:
            entry.x_prev[new] = previous.x_prev[old]
