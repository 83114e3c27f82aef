"""The balance QP of a legged robot: its built-in tasks and constraints on a problem builder."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numba
import numpy as np
import pinocchio as pin

from tasks.base_orientation_task import BaseOrientationTask
from tasks.com_task import ComTask
from tasks.contact_task import ContactTask
from tasks.floating_base_dynamics import FloatingBaseDynamics
from tasks.frame_position_task import FramePositionTask
from tasks.friction_cones import FrictionCones
from tasks.joint_limits import JointLimits
from tasks.posture_task import PostureTask
from tasks.stance_contacts import StanceContacts
from tasks.support_polygon_barrier import SupportPolygonBarrier
from tasks.torque_limits import TorqueLimits
from wbc.controller.contact_schedule import ContactSchedule
from wbc.controller.controller_config import ControllerConfig
from wbc.controller.problem_builder import ProblemBuilder
from wbc.controller.tick_plan import Regularization
from wbc.core.compiled_call import bind_compiled
from wbc.core.errors import ConfigurationError
from wbc.model.description import Go2Description
from wbc.model.kinematics import RobotKinematics
from wbc.model.support_polygon import SupportPolygon

#: Per-tick decay of the orientation integral while not on every foot (0.1 s at 1 kHz).
_INTEGRAL_FADE = 0.99


@numba.njit(cache=True)
def _error_norms(com, base, posture, feet, out):  # pragma: no cover - compiled
    """Euclidean norms of the CoM, base orientation, posture and each foot's task errors
    into ``out`` (3 + feet,)."""
    out[0] = np.sqrt(com @ com)
    out[1] = np.sqrt(base @ base)
    out[2] = np.sqrt(posture @ posture)
    for i in range(len(feet)):
        foot = feet[i]
        out[3 + i] = np.sqrt(foot @ foot)


class BalanceProblem:
    """The tasks and constraints that keep a legged robot balanced, registered on a
    :class:`ProblemBuilder` exactly as a user's own are.

    Tasks: the centre of mass, the base orientation, the joint posture, and one position
    task per foot (active while the foot swings). Constraints:

    - the floating-base rows of the equations of motion ``M_u qdd + h_u = J_u^T f``;
    - stance feet fixed: ``J_c qdd + Jdot_c v = -kd v_c``;
    - torque limits (a fraction of the URDF's) on ``tau = M_a qdd + h_a - J_a^T f``;
    - friction pyramids, with minimum and maximum normal force per stance foot (the
      maximum is the contact schedule's, ramped down to unload a foot);
    - joint position and velocity limits as acceleration bounds;
    - the centre of mass inside the support polygon with a margin, as a soft barrier.

    The first two declare themselves eliminable (:class:`tasks.Elimination`).
    """

    def __init__(self, description: Go2Description, model: pin.Model,
                 kinematics: RobotKinematics, config: ControllerConfig, *, legs: Sequence[str],
                 foot_frames: Sequence[str], foot_radius_m: float,
                 normal_force_bounds: np.ndarray):
        """Args:
            description: The robot's limits and joints.
            model: Its Pinocchio model (the frames the tasks name).
            kinematics: The kinematics every task reads; it computes the feet's frames.
            config: Gains, weights, limits.
            legs: The contacts, in the order of ``foot_frames`` and of the bounds.
            foot_frames: The foot frame of each leg.
            foot_radius_m: The foot spheres' radius [m].
            normal_force_bounds: Each foot's normal-force bound [N] (legs,), updated in
                place by the contact schedule; the friction cones read it every tick.
        """
        gains, weights, limits = config.gains, config.weights, config.limits
        contacts = config.contacts
        self.legs = tuple(legs)
        self.config = config
        self.kinematics = kinematics
        nv = kinematics.nv
        self.com_task = ComTask(kp=gains.com_kp, weight=weights.com_weight)
        self.base_task = BaseOrientationTask(kp=gains.base_orientation_kp,
                                             weight=weights.base_orientation_weight)
        self.posture_task = PostureTask(n_joints=nv - 6, kp=gains.posture_kp,
                                        weight=weights.posture_weight)
        self.foot_tasks = {leg: FramePositionTask(model, frame, kp=gains.foot_kp,
                                                  weight=weights.foot_weight)
                           for leg, frame in zip(self.legs, foot_frames)}
        self.contact_task = ContactTask(model, foot_frames, kd=gains.contact_damping,
                                        radius_m=foot_radius_m)
        self.support = SupportPolygon(margin_m=contacts.support_margin_m)
        self.friction = FrictionCones(len(self.legs), mu=contacts.friction_coefficient,
                                      min_force_n=contacts.min_normal_force_n,
                                      max_force_n=contacts.max_normal_force_n,
                                      max_force=normal_force_bounds)
        self.support_barrier = SupportPolygonBarrier(omega=contacts.support_omega)
        self.torque_limits = TorqueLimits(
            self.contact_task, limits.torque_limit_fraction * description.effort_limit)
        leg_columns = np.array([[6 + j for j in description.leg_joint_indices(leg)]
                                for leg in self.legs])
        #: Stacks the registered tasks and constraints into the tick's QP.
        self.builder = ProblemBuilder(
            kinematics, self.contact_task, self.legs, leg_columns=leg_columns,
            reduce=config.solver.eliminate_dynamics,
            regularization=Regularization(
                acceleration=weights.acceleration_weight, force=weights.force_weight,
                acceleration_rate=weights.acceleration_rate_weight,
                force_rate=weights.force_rate_weight, torque_rate=weights.torque_rate_weight,
                slack={"support": weights.support_slack_weight}))
        for task in (self.com_task, self.base_task, self.posture_task):
            self.builder.add_task(task)
        for task in self.foot_tasks.values():
            self.builder.add_task(task, active=False)
        for constraint in (FloatingBaseDynamics(self.contact_task),
                           StanceContacts(self.contact_task), self.torque_limits,
                           self.friction,
                           JointLimits(description.position_lower, description.position_upper,
                                       description.velocity_limit,
                                       horizon_s=limits.joint_limit_horizon_s),
                           self.support_barrier):
            self.builder.add_constraint(constraint)
        self._foot_rows = {leg: i for i, leg in enumerate(self.legs)}
        self._support: tuple[str, ...] | None = None
        # The schedule's change counts when last followed (-1: follow it anew).
        self._mode_changes = self._support_changes = -1
        self._held = False  # no target before the first hold (the controller's reset)
        #: Each foot's mode as last followed (:meth:`follow`), and the feet in the air.
        self.stance: list[bool] = []
        self.swing_legs: list[str] = []
        self._base_integral = np.zeros(3)
        #: The built-in tasks' error norms [m, rad, rad, m per foot] (3 + legs,), as
        #: :meth:`error_norms_step` last wrote them.
        self.error_norms = np.zeros(3 + len(self.legs))
        # The tasks' error arrays are never replaced: the norms' call is bound once.
        self._error_norms_step = (_error_norms, (
            self.com_task.error, self.base_task.error, self.posture_task.error,
            tuple(self.foot_tasks[leg].error for leg in self.legs), self.error_norms))
        self._error_norms = bind_compiled(_error_norms, *self._error_norms_step[1])
        self._foot_keys = {leg: (leg + "_foot", 3 + i) for i, leg in enumerate(self.legs)}

    @property
    def builtin_tasks(self) -> tuple:
        """The tasks this problem registered (a user's are added beside them)."""
        return (self.com_task, self.base_task, self.posture_task, *self.foot_tasks.values())

    def hold(self, q: np.ndarray) -> None:
        """Every target from the state the kinematics was last updated at: the CoM, the
        base level at its yaw, the joints, the feet; unit posture weights, the feet's
        configured weight."""
        kin = self.kinematics
        self._held = True
        self.com_task.set_target(kin.com_position)
        yaw = pin.rpy.matrixToRpy(kin.base_rotation)[2]
        self.base_task.set_rpy(0.0, 0.0, yaw)
        self.posture_task.set_target(q[7:])
        self.posture_task.set_joint_weights(np.ones(self.posture_task.dim))
        for leg, task in self.foot_tasks.items():
            task.set_target(kin.frame_position[self._foot_rows[leg]])
            task.set_weight(self.config.weights.foot_weight)
        self._base_integral[:] = 0.0
        self._support = None
        self._mode_changes = self._support_changes = -1
        self._polygon_due = True

    def start_swing(self, leg: str) -> None:
        """A foot leaves the ground: its target is where it is, at rest."""
        self.foot_tasks[leg].set_motion(self.kinematics.frame_position[self._foot_rows[leg]])

    def task_errors(self, swing_legs: Sequence[str], *,
                    computed: bool = False) -> dict[str, float]:
        """The built-in tasks' error norms [m, rad] at the last update, the swinging feet's
        as ``<leg>_foot``; ``computed``: as :meth:`error_norms_step` last wrote them (the
        controller's compiled solve runs it), else computed now."""
        if not computed:
            self._error_norms()
        values = self.error_norms.tolist()
        errors = {"com": values[0], "base_orientation": values[1], "posture": values[2]}
        for leg in swing_legs:
            key, index = self._foot_keys[leg]
            errors[key] = values[index]
        return errors

    def error_norms_step(self) -> tuple[Any, tuple]:
        """The norms of :meth:`task_errors` as a step of a compiled program, writing
        :attr:`error_norms` (every foot's, swinging or not)."""
        return self._error_norms_step

    def follow(self, schedule: ContactSchedule, leg: str | None = None, *,
               started: bool = True) -> bool:
        """Follow the contact schedule after a change to ``leg`` (every foot when ``None``):
        a foot's mode sets whether it carries load and whether its task is active (a foot
        that leaves the ground, once ``started``, is held where it is); the fully loaded
        feet are the support polygon's corners from the next tick. Returns whether any
        foot's mode changed (not only a bound)."""
        changes = schedule.mode_changes
        if leg is not None and changes == self._mode_changes:
            # Only a bound changed (a foot being unloaded or reloaded, every tick): the
            # layout stays; the polygon changes when the support set does.
            self._follow_support(schedule)
            return False
        stance = schedule.stance
        self._mode_changes = changes
        if leg is not None and stance == self.stance:  # a mode set to what it was
            self._follow_support(schedule)
            return False
        for name, standing, was in zip(self.legs, stance, self.stance or stance):
            if was and not standing and started:
                self.start_swing(name)
            self.builder.set_active(self.foot_tasks[name], not standing)
        self.builder.set_loaded_contacts([name for name, s in zip(self.legs, stance) if s])
        self.stance = stance
        self.swing_legs = [name for name, s in zip(self.legs, stance) if not s]
        self._support = None
        self._support_changes = -1
        self._follow_support(schedule)
        return True

    def _follow_support(self, schedule: ContactSchedule) -> None:
        changes = schedule.support_changes
        if changes == self._support_changes:  # the same support feet as last followed
            return
        self._support_changes = changes
        support = tuple(schedule.support_legs())
        if support != self._support:
            self._support = support
            self._polygon_due = True

    _polygon_due = True

    def before_update(self) -> None:
        """Per-tick inputs that depend on the state: the polygon (when the support changed)
        and the base orientation's integral."""
        if not self._held:  # the tasks would say "target not set", not how to fix it
            raise ConfigurationError("WholeBodyController.step() before reset(): call "
                                     "controller.reset(q, v) first, with the robot's state")
        if self._polygon_due and self._support is not None:
            self._polygon_due = False
            legs = self._support
            if len(legs) >= 3:
                rows = [self._foot_rows[leg] for leg in legs]
                points = self.kinematics.frame_position[rows, :2]
                self.support_barrier.set_polygon(*self.support.halfplanes(points))
            else:
                self.support_barrier.set_polygon(np.zeros((0, 2)), np.zeros(0))
        # Integral action on the base orientation: joint friction the model lacks holds
        # the base tilted when the proportional term alone needs less torque than it.
        # Only on every foot: with a foot up, a small tilt is the tasks' fair compromise,
        # and the integral would trade the raised foot's tracking for it; it then fades.
        gains = self.config.gains
        ki = gains.base_orientation_ki
        if ki:
            integral = self._base_integral
            if self.swing_legs or len(self._support or ()) < len(self.legs):
                integral *= _INTEGRAL_FADE
            else:
                integral += self.config.solver.control_period_s * self.base_task.error
                np.clip(integral, -gains.base_orientation_integral_limit,
                        gains.base_orientation_integral_limit, out=integral)
            np.multiply(ki, integral, out=self.base_task.bias)

    def hold_at_rest(self, q: np.ndarray) -> np.ndarray:
        """Start the rate costs from holding ``q`` at rest on every foot: the torques [N m]
        that do (returned, a new array; the torque-rate cost's reference) and the feet's
        forces (the force-rate cost's). Updates the kinematics at ``q`` at rest."""
        kin, builder = self.kinematics, self.builder
        kin.compute(q, np.zeros(kin.nv))
        self.contact_task.evaluate(kin)
        gravity = kin.nonlinear_effects.copy()
        jc = self.contact_task.jacobian
        solved = np.linalg.lstsq(jc[:, :6].T, gravity[:6], rcond=None)[0]
        tau = gravity[6:] - jc[:, 6:].T @ solved
        builder.tau_prev[:] = tau
        x_prev = np.zeros(builder.layout.n)
        for i, leg in enumerate(self.legs):
            x_prev[builder.layout.force_slice(leg)] = solved[3 * i:3 * i + 3]
        builder.reset_rates(x_prev)
        return tau
