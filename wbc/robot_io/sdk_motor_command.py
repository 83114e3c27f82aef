"""The motor command as the Unitree SDK's ``rt/lowcmd`` takes it (``LowCmd_.motor_cmd``).

The fields, units, sentinels and the SDK's joint order are in :mod:`wbc.robot_io.unitree_sdk`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector
from wbc.model.description import JOINT_NAMES, UNITREE_SDK_JOINT_NAMES
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS, UNITREE_SDK_ORDERS, Orders
from wbc.robot_io.motor_command import MotorCommand
from wbc.robot_io.unitree_sdk import (
    MODE_ENABLE,
    MODE_STOP,
    POS_STOP_F,
    SDK_LEG_MOTORS,
    SDK_MOTOR_SLOTS,
    VEL_STOP_F,
    set_idle_motor_slots,
)

_SDK = JointMap.unitree_sdk()
# Messages carry float32: recognise a sentinel that went through one.
_SENTINEL_RTOL = 1e-6
_COMMAND_FIELDS = ("mode", "q", "dq", "tau", "kp", "kd")


#: How to reach the description's order, ending an order mismatch's message.
FROM_DESCRIPTION_ONLY = ("pass the controller's command as it is (the description's "
                         "order): this conversion maps it to the SDK's by name")


def _joints(indices: np.ndarray, names: tuple[str, ...]) -> str:
    return ", ".join(f"{i} ({names[i]})" for i in indices)


def _gains(name: str, value: Any, names: tuple[str, ...]) -> np.ndarray:
    gains = as_vector(name, value, SDK_LEG_MOTORS)
    bad = np.flatnonzero(gains < 0.0)
    if len(bad):
        raise ConfigurationError(
            f"{name}: expected gains >= 0, received {gains[bad].tolist()} at "
            f"{_joints(bad, names)}"
        )
    return gains


def _modes(value: Any) -> np.ndarray:
    try:
        modes = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as err:
        raise ConfigurationError(
            f"mode: expected {SDK_LEG_MOTORS} values 0x00 (stop) or 0x01 (enable), "
            f"received {value!r}"
        ) from err
    if modes.shape != (SDK_LEG_MOTORS,):
        raise ConfigurationError(
            f"mode: expected an array of shape ({SDK_LEG_MOTORS},), received shape {modes.shape}"
        )
    bad = np.flatnonzero((modes != MODE_STOP) & (modes != MODE_ENABLE))
    if len(bad):
        raise ConfigurationError(
            f"mode: expected 0x00 (stop) or 0x01 (enable), received {modes[bad].tolist()} at "
            f"slots {_joints(bad, UNITREE_SDK_JOINT_NAMES)}"
        )
    return modes.astype(np.uint8)  # the message's type


def _is_stop(values: np.ndarray, sentinel: float) -> np.ndarray:
    return np.isclose(values, sentinel, rtol=_SENTINEL_RTOL, atol=0.0)


@dataclass
class SdkMotorCommand:
    """The 12 leg entries of ``LowCmd_.motor_cmd``, SDK order (FR, FL, RR, RL).

    Arrays are (12,) and copied on construction. See :mod:`wbc.robot_io.unitree_sdk` for the
    fields, units and sentinels; build one from a controller with :meth:`from_control_output`.

    Example:
        >>> sdk_cmd = SdkMotorCommand.from_control_output(controller.step(...))
        >>> sdk_cmd.write_to(low_cmd)   # then the header fields and the CRC, and publish

    Raises:
        ConfigurationError: A wrong shape, a non-finite value, a negative gain, a mode other
            than 0x00 or 0x01, or a stop sentinel on a motor whose gain would act on it.
    """

    #: Always the Unitree SDK's (motor slots 0 to 11).
    orders: ClassVar[Orders] = UNITREE_SDK_ORDERS
    #: 0x01 enable, 0x00 stop (uint8).
    mode: np.ndarray
    #: Position targets [rad], or :data:`POS_STOP_F` where ``kp = 0``.
    q: np.ndarray
    #: Velocity targets [rad/s], or :data:`VEL_STOP_F` where ``kd = 0``.
    dq: np.ndarray
    #: Feed-forward torques [N m].
    tau: np.ndarray
    #: Position gains [N m/rad].
    kp: np.ndarray
    #: Velocity gains [N m s/rad].
    kd: np.ndarray

    def __post_init__(self) -> None:
        self.mode = _modes(self.mode)
        self.q = as_vector("q", self.q, SDK_LEG_MOTORS)
        self.dq = as_vector("dq", self.dq, SDK_LEG_MOTORS)
        self.tau = as_vector("tau", self.tau, SDK_LEG_MOTORS)
        self.kp = _gains("kp", self.kp, UNITREE_SDK_JOINT_NAMES)
        self.kd = _gains("kd", self.kd, UNITREE_SDK_JOINT_NAMES)
        # A sentinel is a target 2e9 rad away: only safe where no gain multiplies it.
        for name, target, sentinel, gain_name, gain in (
            ("q", self.q, POS_STOP_F, "kp", self.kp),
            ("dq", self.dq, VEL_STOP_F, "kd", self.kd),
        ):
            bad = np.flatnonzero(_is_stop(target, sentinel) & (gain > 0.0))
            if len(bad):
                raise ConfigurationError(
                    f"{name}: the stop sentinel {sentinel:g} with {gain_name} > 0 at slots "
                    f"{_joints(bad, UNITREE_SDK_JOINT_NAMES)}; the driver would chase it: "
                    f"use {gain_name} = 0 there, or a real target"
                )

    @classmethod
    def from_control_output(cls, cmd: MotorCommand, *,
                            use_stop_sentinels: bool = True) -> SdkMotorCommand:
        """The SDK command for a description-order command (a ``ControlOutput`` too).

        Every motor is enabled (``mode = 0x01``); the arrays are reordered by joint name.

        Args:
            cmd: The command, description order (FL, FR, RL, RR): its ``orders`` are
                checked (an object without ``orders`` is taken as in the description's).
            use_stop_sentinels: Write :data:`POS_STOP_F` as ``q`` where ``kp = 0`` and
                :data:`VEL_STOP_F` as ``dq`` where ``kd = 0``, as the SDK's examples do
                (the targets are unused there). Off: the targets are sent as they are.

        Raises:
            OrderMismatchError: ``cmd`` is in another joint order (a robot's, after
                :meth:`MotorCommand.reordered`), named with the description's.
            ConfigurationError: A field of ``cmd`` (named ``cmd.<field>``) with a wrong
                shape, a non-finite value or a negative gain.
        """
        orders = getattr(cmd, "orders", DESCRIPTION_ORDERS)  # a duck-typed command: as before
        if orders is not DESCRIPTION_ORDERS:
            orders.check(DESCRIPTION_ORDERS, what="SdkMotorCommand.from_control_output(cmd)",
                         legs=False, fix=FROM_DESCRIPTION_ONLY)
        q_des = as_vector("cmd.q_des", cmd.q_des, SDK_LEG_MOTORS)
        dq_des = as_vector("cmd.dq_des", cmd.dq_des, SDK_LEG_MOTORS)
        tau_ff = as_vector("cmd.tau_ff", cmd.tau_ff, SDK_LEG_MOTORS)
        kp = _gains("cmd.kp", cmd.kp, JOINT_NAMES)
        kd = _gains("cmd.kd", cmd.kd, JOINT_NAMES)
        i = _SDK.index  # sdk[k] = description[i[k]]
        q, dq, kp, kd = q_des[i], dq_des[i], kp[i], kd[i]
        if use_stop_sentinels:
            q = np.where(kp == 0.0, POS_STOP_F, q)
            dq = np.where(kd == 0.0, VEL_STOP_F, dq)
        return cls(mode=np.full(SDK_LEG_MOTORS, MODE_ENABLE), q=q, dq=dq, tau=tau_ff[i],
                   kp=kp, kd=kd)

    def to_motor_command(self) -> MotorCommand:
        """The same command in the description order, as this library's drivers take it.

        Unused targets come back as zero: ``q_des = 0`` where ``q`` is :data:`POS_STOP_F`
        (``kp`` is 0 there), ``dq_des = 0`` where ``dq`` is :data:`VEL_STOP_F` (``kd`` is
        0 there). A stopped motor (``mode = 0x00``) applies no torque: it comes back as all
        zeros. Everything else is kept, so ``from_control_output`` then ``to_motor_command``
        returns the original command except for the targets a zero gain ignores.
        """
        enabled = self.mode == MODE_ENABLE
        q = np.where(enabled & ~_is_stop(self.q, POS_STOP_F), self.q, 0.0)
        dq = np.where(enabled & ~_is_stop(self.dq, VEL_STOP_F), self.dq, 0.0)
        sdk = MotorCommand(q_des=q, dq_des=dq, kp=np.where(enabled, self.kp, 0.0),
                           kd=np.where(enabled, self.kd, 0.0),
                           tau_ff=np.where(enabled, self.tau, 0.0), orders=UNITREE_SDK_ORDERS)
        return sdk.reordered(_SDK.inverse)

    def torque_at(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """The torque [N m] (12,) the drivers apply at the measured state, SDK order.

        ``tau + kp (q_cmd - q) + kd (dq_cmd - dq)`` at motor positions ``q`` [rad] and
        velocities ``dq`` [rad/s]; zero for a stopped motor. Unclipped.
        """
        q = as_vector("q (measured)", q, SDK_LEG_MOTORS)
        dq = as_vector("dq (measured)", dq, SDK_LEG_MOTORS)
        tau = self.tau + self.kp * (self.q - q) + self.kd * (self.dq - dq)
        return np.where(self.mode == MODE_ENABLE, tau, 0.0)

    def as_20_slots(self) -> dict[str, np.ndarray]:
        """The whole ``motor_cmd`` list: ``{"mode", "q", "dq", "tau", "kp", "kd"}`` -> (20,).

        Keys are the ``MotorCmd_`` attribute names; slots 0 to 11 are this command, slots 12
        to 19 (no GO2 motor) idle as the SDK sends them
        (:func:`~wbc.robot_io.unitree_sdk.set_idle_motor_slots`: enabled, ``q = PosStopF``,
        ``dq = VelStopF``, ``tau = kp = kd = 0``).
        """
        slots: dict[str, np.ndarray] = {}
        for name in _COMMAND_FIELDS:
            values = getattr(self, name)
            slots[name] = np.empty(SDK_MOTOR_SLOTS, dtype=values.dtype)
            slots[name][:SDK_LEG_MOTORS] = values
        set_idle_motor_slots(slots)
        return slots

    def write_to(self, low_cmd: Any) -> None:
        """Set ``low_cmd.motor_cmd[0..19]`` (a ``LowCmd_`` or anything shaped like one): this
        command in slots 0 to 11, slots 12 to 19 idle (:meth:`as_20_slots`).

        Only the motor entries are written: the header (``head``, ``level_flag``) and the
        ``crc``, which the SDK computes over the finished message, are the caller's.

        Raises:
            ConfigurationError: ``low_cmd`` has no ``motor_cmd`` list of 20 entries.
        """
        motors: Any = getattr(low_cmd, "motor_cmd", None)
        if not hasattr(motors, "__len__") or len(motors) != SDK_MOTOR_SLOTS:
            raise ConfigurationError(
                f"low_cmd: expected a LowCmd_ with a motor_cmd list of {SDK_MOTOR_SLOTS} "
                f"entries, received {type(low_cmd).__name__}"
            )
        slots = self.as_20_slots()
        for k, motor in enumerate(motors):
            motor.mode = int(slots["mode"][k])
            for name in _COMMAND_FIELDS[1:]:
                setattr(motor, name, float(slots[name][k]))
