"""A plant of your own behind the robot interface: the loop, the estimator and the actions on it.

Run ``python examples/own_plant.py`` (it prints ``SUCCEEDED: high five done: ...; the FR
foot rose to 0.351 m``). This file builds its own MuJoCo GO2 straight from the URDF, not
this library's simulator: the URDF's convex collision meshes as they are (the feet are
not the controller's spheres), MuJoCo's default contacts, no joint friction, its links
colliding with the floor only, the implicit integrator. It lists its motors in the Unitree
SDK's order, applies the motor drivers' law itself, and reports what its sensors read as a
``wbc.SensorRecord``: MuJoCo's gyroscope and accelerometer at the URDF's IMU, the joint
encoders, and no foot-force sensors, so the estimator takes contact from the controller's
schedule alone (``use_foot_force=False``). ``ControlLoop`` wires it to the state estimator,
the controller and the action servers by joint name, as it would a real GO2; a HighFive
goal then runs on it.

Orders: the plant declares its own (``joint_names``, ``leg_names``: the Unitree SDK's here),
fills its records in them (``SensorRecord.zeros(UNITREE_SDK_ORDERS)``) and gets its commands
in them (``command.orders``). The loop checks both ways and refuses a mismatch, naming both
orders: a record already in the description's order (what ``wbc.sensor_record_from_message``
returns) from a plant that declares the SDK's would otherwise have its feet swapped.
"""

from __future__ import annotations

import re

import mujoco
import numpy as np

from actions import ControlLoop, GoalStatus, HighFiveGoal
from wbc import (
    UNITREE_SDK_JOINT_NAMES,
    UNITREE_SDK_LEGS,
    UNITREE_SDK_ORDERS,
    Go2Description,
    MotorCommand,
    SensorRecord,
    WholeBodyController,
    make_estimator,
)


class UrdfGo2:
    """A GO2 in MuJoCo, built from the URDF, spoken to as a real robot is.

    The :class:`actions.RobotInterface` is five members: ``joint_names`` and ``leg_names``
    (the orders of its arrays), ``time_s``, ``read_sensors()`` and ``write_command()``.
    """

    joint_names = UNITREE_SDK_JOINT_NAMES   # motors FR, FL, RR, RL: mapped by name
    leg_names = UNITREE_SDK_LEGS            # its foot array's order (it has no foot sensors)

    def __init__(self, *, control_period_s: float = 1e-3, timestep_s: float = 1e-3):
        description = Go2Description.default()
        urdf = description.urdf_path.read_text()
        urdf = re.sub(r"<visual>.*?</visual>", "", urdf, flags=re.DOTALL)  # .dae: unread
        urdf = urdf.replace(description.mesh_uri_prefix(), f"{description.folder}/")
        spec = mujoco.MjSpec.from_string(urdf)
        spec.option.timestep = timestep_s
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        for geom in spec.geoms:  # the links touch the floor, not each other
            geom.contype, geom.conaffinity = 2, 1
        base = spec.body("base")
        base.add_freejoint()
        # The IMU, where the URDF has it: MuJoCo's gyroscope and accelerometer sensors.
        base.add_site(name="imu", pos=[-0.02557, 0.0, 0.04232])
        for name, kind in (("gyro", mujoco.mjtSensor.mjSENS_GYRO),
                           ("accel", mujoco.mjtSensor.mjSENS_ACCELEROMETER)):
            spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE,
                            objname="imu")
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                                contype=1, conaffinity=2)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self._qpos = np.array([self.model.joint(n).qposadr[0] for n in self.joint_names])
        self._dof = np.array([self.model.joint(n).dofadr[0] for n in self.joint_names])
        self._effort = np.array([description.effort_limit[description.joint_index(n)]
                                 for n in self.joint_names])
        self._substeps = round(control_period_s / timestep_s)
        self._record = SensorRecord.zeros(UNITREE_SDK_ORDERS)  # its records say their orders
        q = description.pose("standing")  # Pinocchio's (x, y, z, w) -> MuJoCo's (w, x, y, z)
        self.data.qpos[:7] = [*q[:3], q[6], *q[3:6]]
        self.data.qpos[self._qpos] = [q[7 + description.joint_index(n)]
                                      for n in self.joint_names]
        mujoco.mj_forward(self.model, self.data)

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    def read_sensors(self) -> SensorRecord:
        """What its IMU and encoders read now (exact: add your sensors' noise here)."""
        record, data = self._record, self.data
        record.stamp_s, record.tick = float(data.time), record.tick + 1
        record.imu_quaternion_wxyz[:] = data.qpos[3:7]     # a perfect attitude filter
        record.gyroscope_rad_s[:] = data.sensor("gyro").data
        record.accelerometer_m_s2[:] = data.sensor("accel").data
        record.q[:] = data.qpos[self._qpos]
        record.dq[:] = data.qvel[self._dof]
        return record

    def write_command(self, command: MotorCommand) -> None:
        """The drivers' law ``tau_ff + kp (q_des - q) + kd (dq_des - dq)`` every physics
        step of the control period, clipped at the effort limits; ``command`` arrives in
        this plant's order (the loop mapped it by name)."""
        command.orders.check(UNITREE_SDK_ORDERS, what="write_command", legs=False,
                             fix="send it through the ControlLoop, which maps it by name")
        for _ in range(self._substeps):
            q, dq = self.data.qpos[self._qpos], self.data.qvel[self._dof]
            tau = (command.tau_ff + command.kp * (command.q_des - q)
                   + command.kd * (command.dq_des - dq))
            self.data.qfrc_applied[:] = 0.0
            self.data.qfrc_applied[self._dof] = np.clip(tau, -self._effort, self._effort)
            mujoco.mj_step(self.model, self.data)


def run(*, height_m: float = 0.35, hold_seconds: int = 1) -> tuple[GoalStatus, str, float]:
    """A high five on this plant; returns its status, message and the highest the raised
    foot went [m] (this plant's own measure)."""
    plant = UrdfGo2()
    estimator = make_estimator(use_foot_force=False)       # no foot sensors on this plant
    loop = ControlLoop(plant, WholeBodyController(), estimator=estimator)
    loop.spin_for(0.3)                                      # settle on the feet
    calf = plant.model.body("FR_calf").id  # the URDF's fixed foot joint fused it into the calf
    highest = [0.0]

    def watch(*_: object) -> None:
        foot = plant.data.xpos[calf] + plant.data.xmat[calf].reshape(3, 3) @ [0, 0, -0.213]
        highest[0] = max(highest[0], float(foot[2]))

    loop.hooks.append(watch)
    result = loop.client("high_five").send_goal_and_wait(
        HighFiveGoal(target_height=height_m, hold_seconds=hold_seconds), timeout=30.0)
    return result.status, result.result.message, highest[0]


if __name__ == "__main__":
    status, message, highest = run()
    print(f"{status.name}: {message}; the FR foot rose to {highest:.3f} m")
