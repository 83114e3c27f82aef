"""The joint torques as constraint rows without bounds, for a problem builder without torque
limits."""

from __future__ import annotations

import numpy as np

from tasks import constraint_kernels
from tasks.contact_task import ContactTask
from tasks.torque_limits import TorqueLimits


class JointTorques(TorqueLimits):
    """The joint torques as rows without bounds (torque limits of ``constraint_kernels.INF``),
    for a builder that has no constraint that ``gives_torques`` (torque limits) registered: it
    needs them to recover the torques."""

    name = "joint torques"

    def __init__(self, contacts: ContactTask):
        super().__init__(contacts, np.full(contacts.nv - 6, constraint_kernels.INF))
