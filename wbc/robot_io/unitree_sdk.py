"""The Unitree SDK's low-level messages (``rt/lowcmd``, ``rt/lowstate``) as NumPy, without the SDK.

Plain NumPy records with the layout of ``unitree_go.msg.dds_.LowCmd_`` and ``LowState_``
(unitree_sdk2 / unitree_sdk2py); ``unitree_sdk2py`` is never imported. The two methods that
touch a message (:meth:`SdkMotorCommand.write_to`, :meth:`SdkLowState.from_message`) only
read and set its attributes. This module names the fields, orders and constants; the records
are :class:`wbc.robot_io.sdk_motor_command.SdkMotorCommand` and
:class:`wbc.robot_io.sdk_low_state.SdkLowState` (with :func:`sensor_record_from_message`).

Joint orders (always mapped by name through :meth:`wbc.model.joint_map.JointMap.unitree_sdk`;
``SdkLowState.orders`` and ``SdkMotorCommand.orders`` are
:data:`~wbc.model.orders.UNITREE_SDK_ORDERS`, and the records and commands they convert to
carry :data:`~wbc.model.orders.DESCRIPTION_ORDERS`, checked where they are used):

- SDK order, the motor slots 0 to 11 of both messages (legs FR, FL, RR, RL):
  ``FR_hip_joint, FR_thigh_joint, FR_calf_joint, FL_hip_joint, FL_thigh_joint,
  FL_calf_joint, RR_hip_joint, RR_thigh_joint, RR_calf_joint, RL_hip_joint,
  RL_thigh_joint, RL_calf_joint``. Slots 12 to 19 carry no GO2 motor.
- Description order, everywhere else in this library (legs FL, FR, RL, RR):
  ``FL_hip_joint, FL_thigh_joint, FL_calf_joint, FR_hip_joint, FR_thigh_joint,
  FR_calf_joint, RL_hip_joint, RL_thigh_joint, RL_calf_joint, RR_hip_joint,
  RR_thigh_joint, RR_calf_joint``.

:class:`SdkMotorCommand`, one ``motor_cmd`` entry per leg motor, arrays (12,) in SDK order:

- ``mode``: ``0x01`` enable (:data:`MODE_ENABLE`), ``0x00`` stop (:data:`MODE_STOP`).
- ``q`` [rad], ``dq`` [rad/s]: the driver's position and velocity targets.
- ``tau`` [N m]: feed-forward torque.
- ``kp`` [N m/rad], ``kd`` [N m s/rad]: gains, >= 0. The driver applies
  ``tau + kp (q - q_meas) + kd (dq - dq_meas)``.
- With ``kp = 0`` the SDK's examples send ``q = PosStopF`` (:data:`POS_STOP_F`, 2.146e9),
  with ``kd = 0`` ``dq = VelStopF`` (:data:`VEL_STOP_F`, 16000.0): "no target".
- Slots 12 to 19 (no GO2 motor) are sent idle, as the SDK's examples send every motor they do
  not drive (:data:`IDLE_MOTOR_CMD`, written by :func:`set_idle_motor_slots`): enabled, the
  two sentinels as targets, ``tau = kp = kd = 0``, so no torque.

:class:`SdkLowState`, what this library reads from ``LowState_``:

- ``imu_quaternion_wxyz`` (4,): base orientation ``R_world_base`` as ``(w, x, y, z)``,
  scalar first (``imu_state.quaternion``). Pinocchio stores ``(x, y, z, w)``.
- ``gyroscope_rad_s`` (3,) [rad/s]: base angular velocity in the base frame.
- ``accelerometer_m_s2`` (3,) [m/s^2]: specific force in the base frame (+9.81 along the
  base z axis when the robot stands still and level).
- ``q`` [rad], ``dq`` [rad/s], ``tau_est`` [N m]: per motor, (12,) SDK order
  (``motor_state[i].q``, ``.dq``, ``.tau_est``).
- ``foot_force`` (4,): raw sensor counts (int16 in the message, no unit), legs FR, FL, RR,
  RL (SDK leg order).

Not kept: ``imu_state.rpy`` (the quaternion's angles), ``motor_state[i].ddq``, and the
base position and linear velocity, which the robot does not measure: the state estimator
(:class:`wbc.StateEstimator`) provides them from :meth:`SdkLowState.sensor_record` (or
:func:`sensor_record_from_message`, which lets a failing sensor's NaN through to it)::

    estimator.reset(sensor_record_from_message(first_low_state))
    estimate = estimator.update(sensor_record_from_message(low_state), bounds)
    out = controller.step(estimate.q, estimate.v)
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

#: ``motor_cmd[i].mode`` of a motor that follows its command.
MODE_ENABLE = 0x01
#: ``motor_cmd[i].mode`` of a motor that applies no torque.
MODE_STOP = 0x00
#: The SDK's ``PosStopF``: the position target of a motor with no position term (kp = 0).
POS_STOP_F = 2.146e9
#: The SDK's ``VelStopF``: the velocity target of a motor with no velocity term (kd = 0).
VEL_STOP_F = 16000.0
#: Motor slots in ``LowCmd_.motor_cmd`` and ``LowState_.motor_state``.
SDK_MOTOR_SLOTS = 20
#: Slots 0 to 11 are the GO2's leg motors.
SDK_LEG_MOTORS = 12
#: ``motor_cmd[i]`` of a slot nothing drives, as the SDK's examples send it: enabled
#: (``mode = 0x01``), the stop sentinels as targets, no gains, no torque.
IDLE_MOTOR_CMD: Mapping[str, float] = MappingProxyType({
    "mode": MODE_ENABLE, "q": POS_STOP_F, "dq": VEL_STOP_F, "tau": 0.0, "kp": 0.0, "kd": 0.0,
})


def set_idle_motor_slots(motors: Any, slots: slice = slice(SDK_LEG_MOTORS, SDK_MOTOR_SLOTS)
                         ) -> None:
    """Write :data:`IDLE_MOTOR_CMD` into ``slots`` (by default 12 to 19, no GO2 motor).

    The one place that convention is written: :meth:`SdkMotorCommand.as_20_slots` (so
    :meth:`~wbc.robot_io.sdk_motor_command.SdkMotorCommand.write_to`), the ``LowCmd_``
    records of :mod:`wbc.robot_io.dds` and their SDK-default command all call it.

    Args:
        motors: The motor command fields by name, each an array over the 20 slots: a dict of
            arrays, or a structured array of ``MotorCmd_`` records (``record["motor_cmd"]``).
        slots: The slots to set.
    """
    for name, value in IDLE_MOTOR_CMD.items():
        motors[name][slots] = value
