"""The task and constraint registration of a controller built on a problem builder."""

from __future__ import annotations

import numpy as np

# The tasks' modules, not the package: `import tasks` imports wbc, and with it this module,
# before the package has any names (see wbc/__init__.py).
from tasks.constraint import Constraint
from tasks.task import Task
from wbc.backends.qp_problem import QpProblem
from wbc.controller.balance_problem import BalanceProblem
from wbc.controller.problem_builder import ProblemBuilder
from wbc.core.errors import ConfigurationError


class TaskComposition:
    """What :class:`~wbc.controller.whole_body_controller.WholeBodyController` offers to
    compose its QP: tasks and constraints added and removed on its :attr:`builder`, the
    built-in ones (its :attr:`balance`'s) kept."""

    builder: ProblemBuilder
    balance: BalanceProblem

    def add_task(self, task: Task) -> Task:
        """Add a task of your own to the QP's cost (from the next tick); returns it.

        The task reads :attr:`kinematics` (the frames it names must be among the
        controller's: pass them as ``extra_frames``). Example: ``examples/custom_task.py``.
        """
        return self.builder.add_task(task)

    def remove_task(self, task: Task) -> None:
        """Remove a task added with :meth:`add_task`."""
        if task in self.balance.builtin_tasks:
            raise ConfigurationError(f"task: {type(task).__name__} is built in; set its weight "
                                     "to 0 to take it out of the cost")
        self.builder.remove_task(task)

    def add_constraint(self, constraint: Constraint) -> Constraint:
        """Add a constraint of your own to the QP (from the next tick); returns it."""
        return self.builder.add_constraint(constraint)

    def remove_constraint(self, constraint: Constraint) -> None:
        """Remove a constraint (one of yours, or a built-in one to replace it)."""
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
