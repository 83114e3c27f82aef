"""The joint and leg orders a record's arrays are in, carried with the record: :class:`Orders`.

A :class:`~wbc.robot_io.sensor_record.SensorRecord` and a
:class:`~wbc.robot_io.motor_command.MotorCommand` hold per-joint arrays (12,) and, for a
record, per-leg arrays (4,). Their positions mean nothing without the names: the
description's order (joints and feet FL, FR, RL, RR) and the Unitree SDK's (FR, FL, RR, RL)
hold the same numbers at different places, and a record in one read as the other swaps the
feet without any error. Each record and command therefore carries an :class:`Orders`, and
every conversion checks it (:meth:`Orders.check`): a mismatch raises
:class:`~wbc.core.errors.OrderMismatchError` naming both orders and the conversion to use.

The check costs one identity comparison on the 1 kHz path: orders are interned
(:meth:`Orders.of` returns the same object for the same names), so a record in the expected
order is the expected object.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from wbc.core.errors import ConfigurationError, OrderMismatchError
from wbc.model.description import JOINT_NAMES, LEGS, UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS

_PARTS = ("hip", "thigh", "calf")


def _names(field: str, values: Sequence[str], count: int, what: str) -> tuple[str, ...]:
    if isinstance(values, str) or not isinstance(values, Sequence):
        raise ConfigurationError(
            f"{field}: expected {count} {what} names, received {values!r}")
    names = tuple(values)
    if len(names) != count or not all(isinstance(name, str) for name in names):
        raise ConfigurationError(
            f"{field}: expected {count} {what} names, received {list(names)!r}")
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise ConfigurationError(f"{field}: {what} names {repeated} appear more than once")
    return names


def _legs_of(joint_names: tuple[str, ...]) -> tuple[str, ...] | None:
    """The legs, in order, when the joints go leg by leg (hip, thigh, calf): ``None`` else."""
    legs = tuple(joint_names[k].split("_")[0] for k in range(0, len(joint_names), 3))
    expected = tuple(f"{leg}_{part}_joint" for leg in legs for part in _PARTS)
    return legs if expected == joint_names and sorted(legs) == sorted(LEGS) else None


class Orders:
    """The order of a record's joints (12 names) and legs (4 names, a permutation of
    ``FL, FR, RL, RR``).

    Build one with :meth:`of` (interned: the same names give the same object); the library's
    two are :data:`DESCRIPTION_ORDERS` and :data:`UNITREE_SDK_ORDERS`. Two orders are equal
    when their names are; the ``name`` only labels messages.

    Args:
        joint_names: The joints, in the order of the arrays (the robot's names: they may be
            aliases of the description's).
        leg_names: The legs, in the order of the foot arrays.
        name: What to call it in messages (``"the Unitree SDK's"``).

    Raises:
        ConfigurationError: Not 12 distinct joint names, or legs that are not each of
            ``FL, FR, RL, RR`` once.
    """

    __slots__ = ("_hash", "joint_names", "leg_names", "name")
    _interned: ClassVar[dict[tuple[tuple[str, ...], tuple[str, ...]], Orders]] = {}
    _reordered: ClassVar[dict[tuple[int, bytes], tuple[Orders, Orders]]] = {}

    joint_names: tuple[str, ...]
    leg_names: tuple[str, ...]
    _hash: int
    name: str

    def __init__(self, joint_names: Sequence[str], leg_names: Sequence[str], *,
                 name: str = "") -> None:
        joints = _names("joint_names", joint_names, len(JOINT_NAMES), "joint")
        legs = _names("leg_names", leg_names, len(LEGS), "leg")
        if sorted(legs) != sorted(LEGS):
            raise ConfigurationError(
                f"leg_names: expected each of {', '.join(LEGS)} once, received {list(legs)}")
        object.__setattr__(self, "joint_names", joints)
        object.__setattr__(self, "leg_names", legs)
        object.__setattr__(self, "name", str(name))
        object.__setattr__(self, "_hash", hash((joints, legs)))

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"Orders are immutable: cannot set {key}")

    @classmethod
    def of(cls, joint_names: Sequence[str], leg_names: Sequence[str], *,
           name: str = "") -> Orders:
        """The orders of these names: the one object for them (the first ``name`` given
        stays; the description's and the SDK's keep theirs)."""
        key = (tuple(joint_names), tuple(leg_names))
        found = cls._interned.get(key)
        if found is None:
            found = cls._interned[key] = cls(*key, name=name)
        return found

    def __eq__(self, other: object) -> bool:
        if self is other:
            return True
        if not isinstance(other, Orders):
            return NotImplemented
        return self.joint_names == other.joint_names and self.leg_names == other.leg_names

    def __hash__(self) -> int:
        return self._hash

    def __reduce__(self) -> tuple:  # pickled (multiprocessing): interned again on load
        return (_interned_orders, (self.joint_names, self.leg_names, self.name))

    def same_joints(self, other: Orders) -> bool:
        """Whether ``other`` lists the same joints in the same order (legs not compared)."""
        return self is other or self.joint_names == other.joint_names

    def reordered(self, index: np.ndarray) -> Orders:
        """The orders of arrays taken at ``index`` (``new[i] = old[index[i]]``): the joints
        reordered; the legs follow the joints when these go leg by leg, else stay.

        Cached per ``(orders, index)``: a reordering repeated every tick costs a lookup.
        """
        key = (id(self), np.asarray(index, dtype=np.intp).tobytes())
        cached = Orders._reordered.get(key)
        if cached is not None and cached[0] is self:
            return cached[1]
        joints = tuple(self.joint_names[int(i)] for i in index)
        legs = _legs_of(joints) or self.leg_names
        result = Orders.of(joints, legs)
        Orders._reordered[key] = (self, result)  # holds self: its id is not reused
        return result

    def describe(self, *, legs: bool = True) -> str:
        """``the Unitree SDK's orders (joints and feet by leg FR, FL, RR, RL)``: the name
        and the legs' order (the joints' names where they do not go leg by leg); joints
        only with ``legs=False`` (a motor command has no foot array)."""
        label = self.name or "other"
        grouped = _legs_of(self.joint_names)
        joints = (f"by leg {', '.join(grouped)}" if grouped
                  else ", ".join(self.joint_names))
        if not legs:
            return f"{label} joint order ({joints})"
        if grouped == self.leg_names:
            return f"{label} orders (joints and feet by leg {', '.join(self.leg_names)})"
        return f"{label} orders (joints {joints}; feet {', '.join(self.leg_names)})"

    def check(self, expected: Orders, *, what: str, fix: str, legs: bool = True) -> None:
        """Raise unless these orders are ``expected`` (the joints only with ``legs=False``).

        Args:
            expected: The orders the caller's arrays must be in.
            what: The record, named in the message (``"read_sensors()"``).
            fix: How to convert, ending the message.
            legs: Compare the leg order too (``False`` for a motor command).

        Raises:
            OrderMismatchError: ``"<what>: in <these orders>, expected <expected>: <fix>"``.
        """
        if self is expected or (self.joint_names == expected.joint_names
                                and (not legs or self.leg_names == expected.leg_names)):
            return
        raise OrderMismatchError(
            f"{what}: in {self.describe(legs=legs)}, expected {expected.describe(legs=legs)}"
            f": {fix}")

    def __repr__(self) -> str:
        return f"Orders({self.describe()})"


def _interned_orders(joint_names: tuple[str, ...], leg_names: tuple[str, ...],
                     name: str) -> Orders:
    return Orders.of(joint_names, leg_names, name=name)


#: The description's (URDF) orders: joints and feet FL, FR, RL, RR; what the controller and
#: the estimator use, and the orders of a record or command built without any.
DESCRIPTION_ORDERS = Orders.of(JOINT_NAMES, LEGS, name="the description's")
#: The Unitree SDK's orders: motor slots and ``foot_force`` FR, FL, RR, RL (``LowState_``,
#: ``LowCmd_``).
UNITREE_SDK_ORDERS = Orders.of(UNITREE_SDK_JOINT_NAMES, UNITREE_SDK_LEGS,
                               name="the Unitree SDK's")
