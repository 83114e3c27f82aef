"""A cost on a contact's force: pull a foot's force [N] towards a target."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from tasks import task_kernels
from tasks.task import Task
from tasks.task_block import TaskBlock
from tasks.variable_layout import force_variable

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


class ContactForceTask(Task):
    """``weight * row_weights * |f_c - f_target|^2`` on one contact's force (world x, y, z).

    A task on the QP's force variables rather than on its accelerations: its Jacobian is the
    identity over ``force:<contact>``, its drift zero, its desired value the target force
    (plus ``reference[2]``). Use it to share the load between the feet as you choose (a
    foot to carry more, a foot about to be lifted to carry less), with ``row_weights`` to
    pick the axes (``(0, 0, 1)``: the normal force only). While the contact has no force
    variables (the foot is in the air) the term is constant and does nothing.

    The gains' ``kp`` and ``kd`` are unused; ``error`` is zero (the force is only known
    once solved: compare the controller's ``forces`` with :attr:`target`).
    """

    dim = 3

    def __init__(self, contact: str, *, weight: float = 1e-3, target_n: np.ndarray | None = None):
        """Args:
            contact: The contact whose force the task weighs (``"FR"``).
            weight: Cost weight [1/N^2].
            target_n: Target force [N] (world); zero when ``None``.
        """
        self.contact = contact
        self.variables = (force_variable(contact),)
        super().__init__(kp=0.0, kd=0.0, weight=weight, nv=None)
        self.set_target(np.zeros(3) if target_n is None else target_n)

    def setup(self, block: TaskBlock) -> None:
        block.jacobian[:, :] = np.eye(3)

    def set_target(self, force_n: np.ndarray) -> None:
        """Set the target force [N] (3,), world frame; copies it."""
        self._set_reference(f"{self.contact} force", force_n, None)

    def _field(self) -> str:
        return f"{self.contact} force"

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        return task_kernels.force_target, (self.reference, self.desired_acceleration)

    def compute(self, kinematics: RobotKinematics) -> None:
        self.evaluate(kinematics)  # the compiled kernel fills every array
