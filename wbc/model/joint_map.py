"""Mapping between the description's joint order and any other order, built by name."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector, check_name
from wbc.model.description import JOINT_NAMES, UNITREE_SDK_JOINT_NAMES


class JointMap:
    """Reorders per-joint arrays between the description order and another order.

    Built by name, never by position: ``JointMap(["FR_hip_joint", ...])`` maps the
    description's (FL, FR, RL, RR) arrays to an array in the given order and back. The other
    order may also carry other names for the same joints (``aliases``), as a real robot's
    driver or another simulator model does.

    Example:
        >>> sdk = JointMap.unitree_sdk()
        >>> tau_sdk = sdk.to_other(tau)      # description order -> SDK motor order
        >>> q_desc = sdk.from_other(q_sdk)   # SDK motor order -> description order
    """

    def __init__(self, other_names: Sequence[str], *, aliases: dict[str, str] | None = None):
        """Args:
            other_names: The joint names of the other order, one per joint, each once.
            aliases: Optional map from a name in ``other_names`` to the description's name.
        """
        aliases = dict(aliases or {})
        names = [str(n) for n in other_names]
        if len(names) != len(JOINT_NAMES):
            raise ConfigurationError(
                f"other_names: expected {len(JOINT_NAMES)} joint names, received {len(names)}"
            )
        resolved = [aliases.get(n, n) for n in names]
        for name in resolved:
            check_name("joint", name, JOINT_NAMES)
        duplicates = sorted({n for n in resolved if resolved.count(n) > 1})
        if duplicates:
            raise ConfigurationError(f"other_names: duplicate joints {duplicates}")
        self.other_names: tuple[str, ...] = tuple(names)
        #: ``other[i] = description[index[i]]``
        self.index = np.array([JOINT_NAMES.index(n) for n in resolved], dtype=np.intp)
        self.inverse = np.argsort(self.index)

    @classmethod
    def unitree_sdk(cls) -> JointMap:
        """The Unitree SDK's motor order: FR, FL, RR, RL x (hip, thigh, calf)."""
        return cls(UNITREE_SDK_JOINT_NAMES)

    def to_other(self, values: Sequence[float] | np.ndarray) -> np.ndarray:
        """Description order -> other order (12,)."""
        return as_vector("values", values, len(JOINT_NAMES), finite=False)[self.index]

    def from_other(self, values: Sequence[float] | np.ndarray) -> np.ndarray:
        """Other order -> description order (12,)."""
        return as_vector("values", values, len(JOINT_NAMES), finite=False)[self.inverse]

    def __repr__(self) -> str:
        return f"JointMap({list(self.other_names)!r})"
