"""A task's share of the QP's cost, handed to it by the problem builder, and the guard that
keeps a task from replacing an array the QP reads."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wbc.core.errors import ConfigurationError


@dataclass
class TaskBlock:
    """The arrays of one task that the QP's cost reads: ``weight * row_weights *
    (jacobian @ x_vars + drift - desired)^2`` over the task's rows.

    A problem builder hands each registered task a block of views into the stacked task
    rows it allocates once (:meth:`tasks.Task.attach`), as it hands each constraint a
    :class:`tasks.ConstraintBlock`; a task not registered anywhere owns its block.

    Attributes:
        jacobian: (dim, width): its columns span the task's ``variables`` in order.
        drift: (dim,): the task's value of ``J x + drift`` at ``x = 0`` (``Jdot v``).
        desired: (dim,): what ``J x + drift`` should be (a desired acceleration).
        row_weights: (dim,): per-row multipliers of the weight.
        gains: (3,): kp [1/s^2], kd [1/s], weight.
    """

    jacobian: np.ndarray
    drift: np.ndarray
    desired: np.ndarray
    row_weights: np.ndarray
    gains: np.ndarray

    @classmethod
    def owned(cls, dim: int, width: int) -> TaskBlock:
        """A block with arrays of its own (unit row weights, zero gains)."""
        return cls(jacobian=np.zeros((dim, width)), drift=np.zeros(dim), desired=np.zeros(dim),
                   row_weights=np.ones(dim), gains=np.zeros(3))

    def copy_into(self, other: TaskBlock) -> None:
        """Copy every value into ``other`` (same shapes; the Jacobian when it fits)."""
        if other.jacobian.shape == self.jacobian.shape:
            other.jacobian[...] = self.jacobian
        for name in ("drift", "desired", "row_weights", "gains"):
            getattr(other, name)[...] = getattr(self, name)


class InPlace:
    """A task's array that the QP or compiled code reads where it is: read it and write into
    it (``task.row_weights[2] = 0``), never replace it (``task.row_weights = ...`` raises).

    Replacing it would leave the QP reading the old array, unchanged and silent: the error
    says so, naming the task and the attribute. ``block`` names the :class:`TaskBlock` field
    behind it; without one the array is the task's own (its references, errors).
    """

    def __init__(self, block: str | None = None):
        self.block = block

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.slot = "_" + name

    def __get__(self, obj: Any, owner: type | None = None) -> Any:
        if obj is None:
            return self
        try:
            if self.block is None:
                return obj.__dict__[self.slot]
            return getattr(obj.__dict__["_block"], self.block)
        except KeyError:  # read before the task's __init__ made it
            raise AttributeError(f"{type(obj).__name__}.{self.name}: not made yet") from None

    def __set__(self, obj: Any, value: Any) -> None:
        where = ("a view of the QP's task block: the QP reads it" if self.block
                 else "read by the task's compiled kernel")
        raise ConfigurationError(
            f"{type(obj).__name__}.{self.name}: cannot be replaced ({where} where it is, so "
            f"a new array would leave the QP unchanged); write into it instead: "
            f"{self.name}[...] = values")
