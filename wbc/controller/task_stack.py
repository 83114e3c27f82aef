"""The registered tasks' rows stacked into arrays allocated once, each task handed its block."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tasks.task import Task
from tasks.task_block import TaskBlock
from tasks.variable_layout import VariableLayout
from wbc.controller.cost_kernels import TaskRows


class TaskStack:
    """Every registered task's rows in one set of arrays: Jacobian entries (row after row,
    each as wide as its task's variables), drifts, desired values, row weights, and each
    task's gains and whether it is in the QP.

    Made when the registered tasks change (not every tick): it hands each task a
    :class:`tasks.TaskBlock` of views into these arrays (:meth:`tasks.Task.attach`), so the
    tasks write their rows where the cost kernels read them.
    """

    def __init__(self, tasks: Sequence[Task], active: Sequence[bool]):
        """Args:
            tasks: The registered tasks, each bound to the kinematics (its width known).
            active: Whether each task is in the QP.
        """
        self.tasks = tuple(tasks)
        dims = [task.dim for task in self.tasks]
        widths = [task.block.jacobian.shape[1] for task in self.tasks]
        rows = int(sum(dims))
        self.row_offset = np.zeros(rows + 1, dtype=np.int64)
        self.row_offset[1:] = np.cumsum(np.repeat(widths, dims)) if rows else []
        self.jacobian = np.zeros(int(self.row_offset[-1]))
        self.drift = np.zeros(rows)
        self.desired = np.zeros(rows)
        self.row_weights = np.zeros(rows)
        self.row_task = np.repeat(np.arange(len(self.tasks)), dims).astype(np.int64)
        self.gains = np.zeros((len(self.tasks), 3))
        self.active = np.array(active, dtype=np.bool_).reshape(len(self.tasks))
        #: The widest task's number of Jacobian columns.
        self.width = max(widths, default=0)
        start = 0
        for i, (task, dim, width) in enumerate(zip(self.tasks, dims, widths)):
            rows_i = slice(start, start + dim)
            entries = slice(int(self.row_offset[start]), int(self.row_offset[start + dim]))
            task.attach(TaskBlock(jacobian=self.jacobian[entries].reshape(dim, width),
                                  drift=self.drift[rows_i], desired=self.desired[rows_i],
                                  row_weights=self.row_weights[rows_i], gains=self.gains[i]))
            start += dim

    def columns(self, layout: VariableLayout) -> np.ndarray:
        """Each task's column of ``x`` for each of its Jacobian columns in ``layout``
        (tasks, widest); -1 for padding and for variables the layout does not have."""
        columns = np.full((len(self.tasks), self.width), -1, dtype=np.int64)
        for i, task in enumerate(self.tasks):
            mapped = layout.columns(task.variables)
            columns[i, :mapped.size] = mapped
        return columns

    def rows(self, columns: np.ndarray) -> TaskRows:
        """The stacked rows with a layout's ``columns``, as the cost kernels take them."""
        return TaskRows(self.jacobian, self.row_offset, self.drift, self.desired,
                        self.row_weights, self.row_task, self.gains, self.active, columns)

    def set_active(self, task: Task, active: bool) -> None:
        """Put a task in the QP or take it out (read in place by the cost kernels)."""
        self.active[self.tasks.index(task)] = active
