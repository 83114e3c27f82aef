"""The GO2 in MuJoCo: reset to a pose, step with joint torques, read the state and foot forces."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from sim.plant import DEFAULT_PLANT, Plant
from sim.scene import build_go2_spec
from wbc.conventions import mujoco_to_pin, pin_to_mujoco
from wbc.description import FOOT_FRAMES, JOINT_NAMES, LEGS, Go2Description
from wbc.errors import ConfigurationError
from wbc.joint_map import JointMap
from wbc.motor_command import MotorCommand
from wbc.validation import as_float, as_vector, check_name


@dataclass
class _Push:
    body_id: int
    force_n: np.ndarray
    torque_nm: np.ndarray
    end_s: float


class Go2Simulator:
    """A MuJoCo plant of the GO2, spoken to in the description's conventions.

    Motor commands (or bare torques) go in and states come out in the description's joint
    order and in Pinocchio's conventions (see :mod:`wbc.conventions`); the plant's own
    actuator order may differ and is wired by name. Each joint's motor driver applies
    ``tau_ff + kp (q_des - q) + kd (dq_des - dq)``, clipped at the effort limit, at every
    physics step.

    Example:
        >>> sim = Go2Simulator()                     # Menagerie's joints and contacts
        >>> sim = Go2Simulator(plant="ideal")        # frictionless joints
        >>> sim.reset("standing")
        >>> q, v = sim.state()
        >>> sim.step_command(controller.step(q, v), n_steps=2)
    """

    def __init__(
        self,
        *,
        timestep_s: float = 1e-3,
        actuator_order: Sequence[str] | None = None,
        description: Go2Description | None = None,
        plant: Plant | str = DEFAULT_PLANT,
    ):
        """Args:
            timestep_s: Physics timestep [s].
            actuator_order: Joint names in the plant's actuator order (description order by
                default).
            description: The robot files (found automatically by default).
            plant: The physics the controller's model does not know: a
                :class:`sim.plant.Plant` or a preset name (:data:`sim.plant.PLANT_PRESETS`).
        """
        self.description = description or Go2Description()
        self.plant = Plant.preset(plant) if isinstance(plant, str) else plant
        self.spec = build_go2_spec(self.description, timestep_s=timestep_s,
                                   actuator_order=actuator_order, plant=self.plant)
        self.model = self.spec.compile()
        self.data = mujoco.MjData(self.model)
        #: Plant actuator order <-> description order.
        self.actuator_map = JointMap(
            [self.model.joint(self.model.actuator_trnid[i, 0]).name for i in range(self.model.nu)]
        )
        jnt_names = [self.model.joint(i).name for i in range(1, self.model.njnt)]
        if jnt_names != list(JOINT_NAMES):
            raise ConfigurationError(f"MuJoCo joint order {jnt_names} differs from {JOINT_NAMES}")
        self._foot_geom = {
            leg: mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, f"{leg}_foot_sphere")
            for leg in LEGS
        }
        self._floor_geom = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
        self._pushes: list[_Push] = []
        self._force6 = np.zeros(6)
        # Actuator i drives joint ``_actuator_qpos[i]`` (qpos index) / ``_actuator_dof[i]``.
        self._actuator_dof = self.model.jnt_dofadr[self.model.actuator_trnid[:, 0]]
        self._actuator_qpos = self.model.jnt_qposadr[self.model.actuator_trnid[:, 0]]
        self._kp = self.model.actuator_biasprm[:, 1]  # views: written in place
        self._kd = self.model.actuator_biasprm[:, 2]
        self.effort_limit = self.model.actuator_forcerange[:, 1].copy()  # actuator order
        self.reset("standing")

    @property
    def time_s(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    @property
    def timestep_s(self) -> float:
        """Physics timestep [s]."""
        return float(self.model.opt.timestep)

    def reset(self, pose: str | np.ndarray = "standing", v: np.ndarray | None = None) -> None:
        """Reset time to zero and the robot to a named pose or a configuration (19,)."""
        q = self.description.pose(pose) if isinstance(pose, str) else as_vector("q", pose, 19)
        v = np.zeros(18) if v is None else as_vector("v", v, 18)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:], self.data.qvel[:] = pin_to_mujoco(q, v)
        self._pushes.clear()
        mujoco.mj_forward(self.model, self.data)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q (19,), v (18,))`` in Pinocchio convention, description order."""
        return mujoco_to_pin(self.data.qpos, self.data.qvel)

    def step(self, tau: np.ndarray, n_steps: int = 1) -> None:
        """Apply joint torques [N m] (description order) and advance ``n_steps`` timesteps.

        Pure torque control (zero driver gains); torques beyond the effort limits are
        clipped, as a motor driver saturates.
        """
        self.step_actuators(self.actuator_map.to_other(as_vector("tau", tau, 12)), n_steps)

    def step_actuators(self, ctrl: np.ndarray, n_steps: int = 1) -> None:
        """Apply torques in the plant's own actuator order and advance ``n_steps`` timesteps."""
        self.data.ctrl[:] = as_vector("ctrl", ctrl, self.model.nu)
        self._kp[:] = 0.0
        self._kd[:] = 0.0
        self._advance(n_steps)

    def step_command(self, command: MotorCommand, n_steps: int = 1) -> None:
        """Hand a motor command (description order) to the drivers; advance ``n_steps``.

        The drivers apply ``tau_ff + kp (q_des - q) + kd (dq_des - dq)``, clipped at the
        effort limits, at every one of the ``n_steps`` physics steps.
        """
        self.step_actuator_command(command.reordered(self.actuator_map.index), n_steps)

    def step_actuator_command(self, command: MotorCommand, n_steps: int = 1) -> None:
        """:meth:`step_command` with the command in the plant's own actuator order.

        Raises:
            ConfigurationError: A field of the wrong shape, non-finite, or a negative gain
                (nothing is applied).
        """
        problem = command.problems(self.effort_limit)
        if problem:
            raise ConfigurationError(f"motor command: {problem}")
        self.data.ctrl[:] = command.tau_ff + command.kp * command.q_des + command.kd * command.dq_des
        # The actuator force is ctrl + biasprm . (1, q, dq): the driver's PD law.
        np.negative(command.kp, out=self._kp)
        np.negative(command.kd, out=self._kd)
        self._advance(n_steps)

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions [rad] and velocities [rad/s] (12,), the plant's actuator order."""
        return (self.data.qpos[self._actuator_qpos].copy(),
                self.data.qvel[self._actuator_dof].copy())

    def _advance(self, n_steps: int) -> None:
        for _ in range(n_steps):
            self._apply_pushes()
            mujoco.mj_step(self.model, self.data)

    def apply_force(
        self,
        force_n: Sequence[float],
        duration_s: float,
        *,
        body: str = "base",
        torque_nm: Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        """Apply a world-frame force [N] (and torque [N m]) at a body's centre of mass.

        The force starts now and lasts ``duration_s`` of simulated time; several may overlap.
        """
        body_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, body)
        if body_id < 0:
            bodies = [self.model.body(i).name for i in range(1, self.model.nbody)]
            check_name("body", body, bodies)
        self._pushes.append(_Push(
            body_id=body_id,
            force_n=as_vector("force_n", force_n, 3),
            torque_nm=as_vector("torque_nm", torque_nm, 3),
            end_s=self.time_s + as_float("duration_s", duration_s, low=0.0),
        ))

    def _apply_pushes(self) -> None:
        self.data.xfrc_applied[:] = 0.0
        now = self.time_s
        self._pushes = [p for p in self._pushes if p.end_s > now + 1e-12]
        for push in self._pushes:
            self.data.xfrc_applied[push.body_id, :3] += push.force_n
            self.data.xfrc_applied[push.body_id, 3:] += push.torque_nm

    def foot_contact_forces(self) -> dict[str, np.ndarray]:
        """World-frame force [N] the floor exerts on each foot (zero when not touching)."""
        forces = {leg: np.zeros(3) for leg in LEGS}
        geom_leg = {g: leg for leg, g in self._foot_geom.items()}
        for i in range(self.data.ncon):
            contact = self.data.contact[i]
            pair = (contact.geom1, contact.geom2)
            if self._floor_geom not in pair:
                continue
            other = pair[1] if pair[0] == self._floor_geom else pair[0]
            leg = geom_leg.get(other)
            if leg is None:
                continue
            mujoco.mj_contactForce(self.model, self.data, i, self._force6)
            # The contact frame's first row is the normal, pointing from geom1 to geom2; the
            # force acts on geom2 along +normal.
            world = contact.frame.reshape(3, 3).T @ self._force6[:3]
            forces[leg] += world if contact.geom2 == other else -world
        return forces

    def foot_sliding_velocities(self) -> dict[str, np.ndarray]:
        """Horizontal velocity [m/s] of each foot sphere's material point at its bottom.

        This is the sliding velocity of a foot on the floor: zero when the sphere rolls
        without slipping, even though its centre then moves.
        """
        velocity = np.zeros(6)
        out = {}
        for leg, frame in FOOT_FRAMES.items():
            body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, frame)
            mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_BODY, body,
                                     velocity, 0)
            angular, linear = velocity[:3], velocity[3:]
            # Point d = (0, 0, -r) below the centre: v + omega x d.
            r = self.model.geom_size[self._foot_geom[leg], 0]
            out[leg] = np.array([linear[0] - r * angular[1], linear[1] + r * angular[0]])
        return out

    def foot_positions(self) -> dict[str, np.ndarray]:
        """World position [m] of each foot frame (the foot sphere's centre)."""
        return {
            leg: self.data.xpos[
                mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, frame)
            ].copy()
            for leg, frame in FOOT_FRAMES.items()
        }
