"""The GO2 scene's scenery: the floor, sky, light and link colours change nothing physical."""

from __future__ import annotations

import functools

import mujoco
import numpy as np
import pytest

import sim.simulator
from actions import HighFiveGoal
from sim.control_loop import ControlLoop
from sim.scene import LINK_RGBA, build_go2_spec

#: Compiled fields the scenery may change: what is drawn, and the name and size bookkeeping
#: of the assets it adds (materials, textures, a light).
VISUAL_PREFIXES = ("geom_rgba", "geom_matid", "light_", "mat_", "tex_", "name_", "names")
VISUAL_FIELDS = {"nmat", "ntex", "ntexdata", "nnames", "nnames_map", "nbuffer", "signature"}


def _fields(model: mujoco.MjModel) -> dict[str, object]:
    """Every array and number of a compiled model, and those of its option and statistics."""
    fields = {}
    for name in dir(model):
        value = getattr(model, name)
        if name.startswith("_") or callable(value):
            continue
        if isinstance(value, (np.ndarray, int, float, str, bytes)):
            fields[name] = value
    for struct in ("opt", "stat"):
        record = getattr(model, struct)
        for name in dir(record):
            value = getattr(record, name)
            if not name.startswith("_") and not callable(value):
                fields[f"{struct}.{name}"] = value
    return fields


def _equal(a: object, b: object) -> bool:
    if isinstance(a, np.ndarray):
        return a.shape == np.shape(b) and np.array_equal(a, b, equal_nan=True)
    return a == b


@pytest.fixture(scope="module")
def models() -> tuple[mujoco.MjModel, mujoco.MjModel]:
    """The plain scene and the dressed one, the same robot and plant."""
    return build_go2_spec(scenery=False).compile(), build_go2_spec().compile()


def test_scenery_changes_only_visual_fields_of_the_compiled_model(models):
    plain, dressed = (_fields(m) for m in models)
    assert plain.keys() == dressed.keys()
    changed = {name for name in plain if not _equal(plain[name], dressed[name])}
    physical = {name for name in changed
                if not name.startswith(VISUAL_PREFIXES) and name not in VISUAL_FIELDS}
    assert physical == set()
    # It does change the look (the test above would pass on a no-op).
    assert {"geom_rgba", "geom_matid", "nmat", "ntex", "light_type"} <= changed
    # Bodies, joints, geoms, meshes and actuators keep their names and order.
    for kind, count in ((mujoco.mjtObj.mjOBJ_BODY, "nbody"), (mujoco.mjtObj.mjOBJ_JOINT, "njnt"),
                        (mujoco.mjtObj.mjOBJ_GEOM, "ngeom"), (mujoco.mjtObj.mjOBJ_MESH, "nmesh"),
                        (mujoco.mjtObj.mjOBJ_ACTUATOR, "nu")):
        names = [[mujoco.mj_id2name(m, kind, i) for i in range(getattr(m, count))]
                 for m in models]
        assert names[0] == names[1]


def test_scenery_has_a_checker_floor_a_sky_a_shadow_and_coloured_links(models):
    _, model = models
    floor = model.geom("floor")
    material = model.mat_texid[floor.matid[0]]
    texture = material[mujoco.mjtTextureRole.mjTEXROLE_RGB]
    assert model.tex_type[texture] == mujoco.mjtTexture.mjTEXTURE_2D
    assert mujoco.mjtTexture.mjTEXTURE_SKYBOX in model.tex_type
    assert model.nlight == 1 and model.light_castshadow[0]
    rgba = {model.body(model.geom_bodyid[i]).name: tuple(model.geom_rgba[i])
            for i in range(model.ngeom)}
    assert rgba["base"] == pytest.approx(LINK_RGBA["base"])
    assert rgba["FR_thigh"] == pytest.approx(LINK_RGBA["thigh"])
    assert rgba["RL_calf"] == pytest.approx(LINK_RGBA["calf"])
    assert rgba["RR_foot"] == pytest.approx(LINK_RGBA["foot"])
    # Light body, dark legs: the body stands out.
    assert min(LINK_RGBA["base"][:3]) > 2 * max(LINK_RGBA["thigh"][:3])


def _high_five_states(seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """qpos and qvel of every tick of a high five's first ``seconds`` of simulated time."""
    loop = ControlLoop.simulated()
    loop.client("high_five").send_goal_async(HighFiveGoal(target_height=0.4, hold_seconds=1))
    qpos, qvel = [], []
    while loop.robot.time_s < seconds - 1e-9:
        loop.spin_once()
        qpos.append(loop.sim.data.qpos.copy())
        qvel.append(loop.sim.data.qvel.copy())
    return np.array(qpos), np.array(qvel)


def test_a_closed_loop_run_is_bit_identical_with_and_without_the_scenery(monkeypatch):
    # 1.8 s: the CoM shifts, the foot unloads, leaves the ground and rises.
    dressed = _high_five_states(1.8)
    monkeypatch.setattr(sim.simulator, "build_go2_spec",
                        functools.partial(build_go2_spec, scenery=False))
    plain = _high_five_states(1.8)
    assert dressed[0].shape == (1800, 19)
    for a, b in zip(dressed, plain, strict=True):
        assert a.tobytes() == b.tobytes()
    # The robot did move: the raised foot is up by then (base roll and height changed).
    assert np.ptp(dressed[0][:, 2]) > 1e-3
