"""The GO2 MuJoCo scene, built from the same URDF as the Pinocchio model."""

from __future__ import annotations

import re
from collections.abc import Sequence

import mujoco
import numpy as np

from sim.plant import DEFAULT_PLANT, Plant
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, check_name
from wbc.model.description import FOOT_FRAMES, FOOT_RADIUS_M, JOINT_NAMES, Go2Description

#: Collision groups: robot geoms touch the floor but not each other.
_ROBOT_CONTYPE, _ROBOT_CONAFFINITY = 2, 1
_FLOOR_CONTYPE, _FLOOR_CONAFFINITY = 1, 2
#: Radius [m] of the site whose touch sensor reads a foot's normal force: beyond any foot
#: sphere a plant may have (at most 0.05 m), and only the foot's own geom counts.
TOUCH_SITE_RADIUS_M = 0.06


def build_go2_spec(
    description: Go2Description | None = None,
    *,
    timestep_s: float = 1e-3,
    actuator_order: Sequence[str] | None = None,
    plant: Plant | str = DEFAULT_PLANT,
    scenery: bool = True,
) -> mujoco.MjSpec:
    """A MuJoCo spec of the GO2 on a flat floor, ready to compile.

    The URDF's collision meshes are kept (its ``.dae`` visuals, which MuJoCo cannot read,
    are dropped); each foot mesh is replaced by a sphere centred on the foot frame; the base
    floats on a free joint. Each joint has a motor driver: an actuator whose force is
    ``ctrl - kp q - kd dq`` (affine bias), clipped at the URDF effort limit, so that with
    ``ctrl = tau_ff + kp q_des + kd dq_des`` it applies the GO2 driver law
    ``tau_ff + kp (q_des - q) + kd (dq_des - dq)`` at every physics step (and MuJoCo's
    implicit integrator treats its damping implicitly, as a fast driver loop would be).

    Args:
        description: The robot files; found from the installed example-robot-data by default.
        timestep_s: Physics timestep [s].
        actuator_order: Joint names in the order the actuators are listed (description order
            by default); another order, e.g. the Unitree SDK's, is wired by name.
        plant: The physics the controller's model does not know (joint friction, contacts,
            payload): a :class:`sim.plant.Plant` or a preset's name.
        scenery: Dress the scene for the viewer and videos (:func:`add_scenery`): a checker
            floor, a sky, a shadow-casting light and coloured links. Visual only; ``False``
            gives a plain grey scene with the same physics.
    """
    description = description or Go2Description.default()
    timestep_s = as_float("timestep_s", timestep_s, low=1e-5, high=0.01)
    if isinstance(plant, str):
        plant = Plant.preset(plant)
    elif not isinstance(plant, Plant):
        raise ConfigurationError(
            f"plant: expected a Plant or a preset name, received {plant!r}")
    order = list(JOINT_NAMES if actuator_order is None else actuator_order)
    for name in order:
        check_name("joint", name, JOINT_NAMES)
    if sorted(order) != sorted(JOINT_NAMES):
        raise ConfigurationError(
            f"actuator_order: expected each of the 12 GO2 joints once, received {order}"
        )

    text = description.urdf_path.read_text()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.DOTALL)
    text = text.replace(description.mesh_uri_prefix(), f"{description.folder}/")
    spec = mujoco.MjSpec.from_string(text)
    spec.compiler.fusestatic = False  # keep the base and the foot bodies
    spec.option.timestep = timestep_s
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST

    spec.body("base").add_freejoint(name="root")

    for geom in spec.geoms:
        geom.contype, geom.conaffinity = _ROBOT_CONTYPE, _ROBOT_CONAFFINITY
    for leg, frame in FOOT_FRAMES.items():
        foot = spec.body(frame)
        for geom in list(foot.geoms):
            spec.delete(geom)
        foot.add_geom(
            name=f"{leg}_foot_sphere",
            type=mujoco.mjtGeom.mjGEOM_SPHERE,
            size=[FOOT_RADIUS_M, 0, 0],
            contype=_ROBOT_CONTYPE,
            conaffinity=_ROBOT_CONAFFINITY,
            # Stiff, well-damped contact: 5 ms time constant at critical damping.
            solref=[0.005, 1.0],
            solimp=[0.95, 0.99, 0.001, 0.5, 2.0],
            mass=0,
        )
        # The foot's normal force, for the simulated foot-force sensor (sim.sensors): a
        # touch sensor sums the normal forces of the contacts inside its site, on its body.
        foot.add_site(name=f"{leg}_foot_touch", type=mujoco.mjtGeom.mjGEOM_SPHERE,
                      size=[TOUCH_SITE_RADIUS_M, 0, 0], group=5)
        spec.add_sensor(name=f"{leg}_foot_touch", type=mujoco.mjtSensor.mjSENS_TOUCH,
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=f"{leg}_foot_touch")

    world = spec.worldbody
    world.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[0, 0, 0.05],
        contype=_FLOOR_CONTYPE,
        conaffinity=_FLOOR_CONAFFINITY,
        rgba=[0.75, 0.78, 0.8, 1.0],
    )
    world.add_light(pos=[0, 0, 3], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)

    effort = dict(zip(JOINT_NAMES, description.effort_limit))
    for name in order:
        spec.add_actuator(
            name=name.removesuffix("_joint"),
            target=name,
            trntype=mujoco.mjtTrn.mjTRN_JOINT,
            gaintype=mujoco.mjtGain.mjGAIN_FIXED,
            gainprm=[1.0] + [0.0] * 9,
            biastype=mujoco.mjtBias.mjBIAS_AFFINE,
            biasprm=[0.0] * 10,  # [0, -kp, -kd], set per command
            ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE,
            forcelimited=mujoco.mjtLimited.mjLIMITED_TRUE,
            forcerange=[-effort[name], effort[name]],
        )
    plant.apply(spec)
    if scenery:
        add_scenery(spec)
    return spec


#: Link colours by body name prefix after the leg's (``FR_thigh`` -> ``thigh``): a light
#: body over dark legs, each leg segment a shade apart, and black rubber feet. The overlays
#: (:mod:`sim.scene_overlay`) keep the saturated colours for themselves.
LINK_RGBA = {
    "base": (0.86, 0.87, 0.89, 1.0),
    "hip": (0.42, 0.44, 0.47, 1.0),
    "thigh": (0.30, 0.32, 0.36, 1.0),
    "calf": (0.18, 0.19, 0.21, 1.0),
    "foot": (0.06, 0.06, 0.06, 1.0),
}


def add_scenery(spec: mujoco.MjSpec) -> None:
    """Dress a GO2 spec for people to look at, in place, changing no physical quantity.

    A checker floor (25 cm squares with thin lines), a sky that fades from blue to white at
    the horizon, a spot light that follows the robot and casts its shadow, a softer head
    light, and the links coloured by segment (:data:`LINK_RGBA`). Only textures, materials,
    colours, lights and the visual options change: no geom, body or joint is added or
    moved, so the compiled model's dynamics and contacts are those of the plain scene
    (``tests/test_scene.py`` checks every field).
    """
    # The URDF parser discards visual-only content by default, textures and materials too;
    # keep them, and delete by hand what it would have discarded: the foot mesh, whose
    # geoms the foot spheres replaced.
    spec.compiler.discardvisual = False
    used = {geom.meshname for geom in spec.geoms}
    for mesh in list(spec.meshes):
        if mesh.name not in used:
            spec.delete(mesh)
    spec.add_texture(name="sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.42, 0.62, 0.85],
                     rgb2=[0.95, 0.97, 1.0], width=256, height=1536)
    spec.add_texture(name="checker", type=mujoco.mjtTexture.mjTEXTURE_2D,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, rgb1=[0.36, 0.40, 0.45],
                     rgb2=[0.46, 0.50, 0.55], mark=mujoco.mjtMark.mjMARK_EDGE,
                     markrgb=[0.62, 0.66, 0.70], width=256, height=256)
    floor_material = spec.add_material(name="floor", texrepeat=[2.0, 2.0], texuniform=True,
                                       reflectance=0.0)
    floor_material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "checker"
    for geom in spec.geoms:
        if geom.name == "floor":
            geom.material = "floor"
            geom.rgba = [1.0, 1.0, 1.0, 1.0]
            continue
        body = geom.parent.name
        part = "base" if body == "base" else body.split("_", 1)[-1]
        geom.rgba = list(LINK_RGBA.get(part, LINK_RGBA["base"]))
    for light in list(spec.lights):
        spec.delete(light)
    # A spot light from the front left and high, following the robot's centre of mass: the
    # shadow falls behind the robot and to its right, onto the floor the video's camera sees.
    # (A slanted directional light's shadow map left acne on the floor around the robot.)
    direction = np.array([-0.35, -0.25, -1.0])
    direction /= np.linalg.norm(direction)
    spec.worldbody.add_light(name="key", type=mujoco.mjtLightType.mjLIGHT_SPOT,
                             pos=list(-3.0 * direction), dir=list(direction), cutoff=40.0,
                             castshadow=True, mode=mujoco.mjtCamLight.mjCAMLIGHT_TRACKCOM,
                             diffuse=[0.75, 0.75, 0.72], specular=[0.2, 0.2, 0.2],
                             ambient=[0.0, 0.0, 0.0])
    visual = spec.visual
    visual.headlight.ambient = [0.32, 0.32, 0.34]
    visual.headlight.diffuse = [0.35, 0.35, 0.35]
    visual.headlight.specular = [0.05, 0.05, 0.05]
    visual.rgba.haze = [0.88, 0.92, 0.97, 1.0]
    visual.quality.shadowsize = 2048
