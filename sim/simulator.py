"""The GO2 in MuJoCo: reset to a pose, step with joint torques, read the state and foot forces."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numba
import numpy as np

from sim.plant import DEFAULT_PLANT, Plant
from sim.scene import build_go2_spec
from wbc.core.conventions import mujoco_to_pin, pin_to_mujoco
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, as_vector, check_name
from wbc.model.description import FOOT_FRAMES, JOINT_NAMES, LEGS, Go2Description
from wbc.model.joint_map import JointMap
from wbc.model.orders import DESCRIPTION_ORDERS
from wbc.robot_io.motor_command import MotorCommand, command_fine

_VECTOR = numba.float64[:]
_CONTIGUOUS = numba.float64[::1]


@numba.njit(numba.boolean(_CONTIGUOUS, _CONTIGUOUS, _CONTIGUOUS, _CONTIGUOUS), cache=True,
            error_model="numpy")
def _pin_state(qpos, qvel, q, v):
    """:func:`wbc.core.conventions.mujoco_to_pin` into ``q``, ``v``; False on a non-finite entry.

    The same arithmetic (NumPy's BLAS may round the last bit differently): the quaternion
    ``(w, x, y, z) -> (x, y, z, w)`` and the free joint's linear velocity from the world
    frame into the base frame, ``R^T v_world``.
    """
    finite = True
    for i in range(q.shape[0]):
        q[i] = qpos[i]
        finite = finite and math.isfinite(qpos[i])
    for i in range(v.shape[0]):
        v[i] = qvel[i]
        finite = finite and math.isfinite(qvel[i])
    w, x, y, z = qpos[3], qpos[4], qpos[5], qpos[6]
    q[3], q[4], q[5], q[6] = x, y, z, w
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)
    r10, r11, r12 = 2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)
    r20, r21, r22 = 2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)
    a, b, c = qvel[0], qvel[1], qvel[2]
    v[0] = r00 * a + r10 * b + r20 * c
    v[1] = r01 * a + r11 * b + r21 * c
    v[2] = r02 * a + r12 * b + r22 * c
    return finite


@numba.njit(numba.boolean(_CONTIGUOUS, _VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR, _VECTOR,
                          _VECTOR, _VECTOR), cache=True)
def _drive(ctrl, kp_bias, kd_bias, q_des, dq_des, kp, kd, tau_ff, effort_limit):
    """The drivers' law as MuJoCo's actuators, ``ctrl + biasprm . (1, q, dq)``, written only
    when a driver takes the command; False (nothing written) when it would refuse it.

    Taken: the shapes (n,), finite values, gains >= 0, ``|tau_ff| <= effort_limit``, by
    :func:`~wbc.robot_io.motor_command.command_fine`, the check
    :meth:`~wbc.robot_io.motor_command.MotorCommand.problems` makes (it and this write in one
    compiled call). ``ctrl = tau_ff + kp q_des + kd dq_des`` (NumPy's order of
    operations: the same bits), ``biasprm[:, 1] = -kp``, ``biasprm[:, 2] = -kd``.
    """
    n = effort_limit.shape[0]
    if ctrl.shape[0] != n or not command_fine(q_des, dq_des, kp, kd, tau_ff, effort_limit):
        return False
    for i in range(n):
        ctrl[i] = tau_ff[i] + kp[i] * q_des[i] + kd[i] * dq_des[i]
        kp_bias[i] = -kp[i]
        kd_bias[i] = -kd[i]
    return True


@dataclass
class _Push:
    body_id: int
    force_n: np.ndarray
    torque_nm: np.ndarray
    end_s: float


class Go2Simulator:
    """A MuJoCo plant of the GO2, spoken to in the description's conventions.

    Motor commands (or bare torques) go in and states come out in the description's joint
    order and in Pinocchio's conventions (see :mod:`wbc.core.conventions`); the plant's own
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
        self.description = description or Go2Description.default()
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
        #: Foot geom id -> its leg's row in LEGS order.
        self._geom_row = {g: LEGS.index(leg) for leg, g in self._foot_geom.items()}
        self._foot_body = np.array([
            mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, FOOT_FRAMES[leg])
            for leg in LEGS], dtype=np.intp)
        self._foot_radius = [float(self.model.geom_size[self._foot_geom[leg], 0]) for leg in LEGS]
        self._pushes: list[_Push] = []
        self._xfrc_dirty = False  # a push wrote xfrc_applied since it was last zeroed
        self._force6 = np.zeros(6)
        self._velocity6 = np.zeros(6)
        # MjData's arrays stay where they are for its whole life: views taken once.
        self._qpos, self._qvel = self.data.qpos, self.data.qvel
        self._ctrl, self._xfrc = self.data.ctrl, self.data.xfrc_applied
        self._xpos = self.data.xpos
        self._kp = self.model.actuator_biasprm[:, 1]  # views: written in place
        self._kd = self.model.actuator_biasprm[:, 2]
        self.effort_limit = self.model.actuator_forcerange[:, 1].copy()  # actuator order
        #: Actuator i drives the joint at qpos index ``actuator_qpos[i]`` and qvel index
        #: ``actuator_dof[i]``.
        joints = self.model.actuator_trnid[:, 0]
        self.actuator_qpos = np.ascontiguousarray(self.model.jnt_qposadr[joints], dtype=np.intp)
        self.actuator_dof = np.ascontiguousarray(self.model.jnt_dofadr[joints], dtype=np.intp)
        touch = [self.model.sensor(f"{leg}_foot_touch") for leg in LEGS]
        start = touch[0].adr[0]
        if [int(t.adr[0]) for t in touch] != list(range(start, start + len(LEGS))):
            raise ConfigurationError("the feet's touch sensors are not consecutive in sensordata")
        self._touch = self.data.sensordata[start:start + len(LEGS)]
        self._actuator_force = self.data.actuator_force
        self._nq, self._nv = self.model.nq, self.model.nv
        self.reset("standing")

    @property
    def time_s(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    @property
    def qpos(self) -> np.ndarray:
        """MuJoCo's generalized positions (a live view: read, never write)."""
        return self._qpos

    @property
    def qvel(self) -> np.ndarray:
        """MuJoCo's generalized velocities (world linear, body angular; a live view)."""
        return self._qvel

    def foot_normal_forces(self) -> np.ndarray:
        """Normal force [N] on each foot (4,), ``LEGS`` order, at the last step (a live view).

        MuJoCo's touch sensors: the sum of the normal forces of each foot's contacts, as
        computed in the last physics step.
        """
        return self._touch

    def actuator_torque(self) -> np.ndarray:
        """Torque [N m] each motor applied in the last step (12,), the plant's actuator
        order (a live view): the drivers' law, clipped at the effort limits."""
        return self._actuator_force

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
        self._xfrc_dirty = False  # mj_resetData zeroed it
        mujoco.mj_forward(self.model, self.data)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q (19,), v (18,))`` in Pinocchio convention, description order (new arrays).

        :func:`wbc.core.conventions.mujoco_to_pin`, compiled (the base's linear velocity may
        differ in its last bit); a non-finite state raises as it does.

        Raises:
            NonFiniteError: A NaN or infinite position or velocity (a diverged simulation).
        """
        q = np.empty(self._nq)
        v = np.empty(self._nv)
        if not _pin_state(self._qpos, self._qvel, q, v):
            mujoco_to_pin(self._qpos, self._qvel)  # raises, naming the entries
        return q, v

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

        Raises:
            OrderMismatchError: ``command`` in another joint order (``command.orders``).
        """
        if command.orders is not DESCRIPTION_ORDERS:
            command.orders.check(DESCRIPTION_ORDERS, what="Go2Simulator.step_command(command)",
                                 legs=False, fix="a command in the plant's actuator order goes "
                                 "to step_actuator_command")
        self.step_actuator_command(command.reordered(self.actuator_map.index), n_steps)

    def step_actuator_command(self, command: MotorCommand, n_steps: int = 1) -> None:
        """:meth:`step_command` with the command in the plant's own actuator order.

        Raises:
            ConfigurationError: A field of the wrong shape, non-finite, or a negative gain
                (nothing is applied).
        """
        # The actuator force is ctrl + biasprm . (1, q, dq): the driver's PD law. A command
        # of float64 vectors is checked and written in one compiled call.
        try:
            taken = _drive(self._ctrl, self._kp, self._kd, command.q_des, command.dq_des,
                           command.kp, command.kd, command.tau_ff, self.effort_limit)
        except TypeError:  # not float64 vectors
            taken = False
        if not taken:
            problem = command.problems(self.effort_limit)
            if problem:
                raise ConfigurationError(f"motor command: {problem}")
            self._ctrl[:] = (command.tau_ff + command.kp * command.q_des
                             + command.kd * command.dq_des)
            np.negative(command.kp, out=self._kp)
            np.negative(command.kd, out=self._kd)
        if self._pushes or self._xfrc_dirty:
            self._advance(n_steps)
        elif n_steps > 0:  # _advance's common case, without its call: one step call
            mujoco.mj_step(self.model, self.data, n_steps)

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions [rad] and velocities [rad/s] (12,), the plant's actuator order."""
        return (self.data.qpos[self.actuator_qpos], self.data.qvel[self.actuator_dof])

    def _advance(self, n_steps: int) -> None:
        if not (self._pushes or self._xfrc_dirty):  # no force to apply or to clear
            if n_steps > 0:
                mujoco.mj_step(self.model, self.data, n_steps)
            return
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
        xfrc = self._xfrc
        xfrc[:] = 0.0
        now = self.time_s
        self._pushes = [p for p in self._pushes if p.end_s > now + 1e-12]
        for push in self._pushes:
            xfrc[push.body_id, :3] += push.force_n
            xfrc[push.body_id, 3:] += push.torque_nm
        self._xfrc_dirty = bool(self._pushes)

    def foot_contact_forces(self) -> dict[str, np.ndarray]:
        """World-frame force [N] the floor exerts on each foot (zero when not touching)."""
        forces = self.foot_contact_force_array()
        return {leg: forces[i] for i, leg in enumerate(LEGS)}

    def foot_contact_force_array(self, out: np.ndarray | None = None) -> np.ndarray:
        """:meth:`foot_contact_forces` as rows (4, 3) in ``LEGS`` order, into ``out`` if given."""
        forces = np.zeros((len(LEGS), 3)) if out is None else out
        forces[:] = 0.0
        ncon = self.data.ncon
        if ncon == 0:
            return forces
        contact = self.data.contact
        floor, rows = self._floor_geom, self._geom_row
        frames = None
        for i, (geom1, geom2) in enumerate(contact.geom.tolist()):
            if geom1 == floor:
                row, sign = rows.get(geom2), 1.0
            elif geom2 == floor:
                row, sign = rows.get(geom1), -1.0
            else:
                continue
            if row is None:
                continue
            if frames is None:
                frames = contact.frame
            mujoco.mj_contactForce(self.model, self.data, i, self._force6)
            # The contact frame's first row is the normal, pointing from geom1 to geom2; the
            # force acts on geom2 along +normal.
            world = frames[i].reshape(3, 3).T @ self._force6[:3]
            if sign > 0.0:
                forces[row] += world
            else:
                forces[row] -= world
        return forces

    def foot_sliding_velocities(self) -> dict[str, np.ndarray]:
        """Horizontal velocity [m/s] of each foot sphere's material point at its bottom.

        This is the sliding velocity of a foot on the floor: zero when the sphere rolls
        without slipping, even though its centre then moves.
        """
        sliding = self.foot_sliding_velocity_array()
        return {leg: sliding[i] for i, leg in enumerate(LEGS)}

    def foot_sliding_velocity_array(self, out: np.ndarray | None = None) -> np.ndarray:
        """:meth:`foot_sliding_velocities` as rows (4, 2) in ``LEGS`` order (into ``out``)."""
        sliding = np.empty((len(LEGS), 2)) if out is None else out
        velocity = self._velocity6
        for i, body in enumerate(self._foot_body.tolist()):
            mujoco.mj_objectVelocity(self.model, self.data, mujoco.mjtObj.mjOBJ_BODY, body,
                                     velocity, 0)
            # Point d = (0, 0, -r) below the centre: v + omega x d.
            r = self._foot_radius[i]
            sliding[i, 0] = velocity[3] - r * velocity[1]
            sliding[i, 1] = velocity[4] + r * velocity[0]
        return sliding

    def foot_positions(self) -> dict[str, np.ndarray]:
        """World position [m] of each foot frame (the foot sphere's centre)."""
        positions = self.foot_position_array()
        return {leg: positions[i] for i, leg in enumerate(LEGS)}

    def foot_position_array(self, out: np.ndarray | None = None) -> np.ndarray:
        """:meth:`foot_positions` as rows (4, 3) in ``LEGS`` order (into ``out`` if given)."""
        if out is None:
            return self._xpos[self._foot_body]
        np.take(self._xpos, self._foot_body, axis=0, out=out)
        return out
