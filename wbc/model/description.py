"""The GO2 description from example-robot-data: joint names and order, feet, named poses, limits."""

from __future__ import annotations

import importlib.metadata
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path

import numpy as np
import pinocchio as pin

from wbc.core.errors import DescriptionNotFoundError
from wbc.core.validation import check_name

#: Legs in the URDF's order.
LEGS: tuple[str, ...] = ("FL", "FR", "RL", "RR")
#: The Unitree SDK's motor order (legs FR, FL, RR, RL; hip, thigh, calf in each).
UNITREE_SDK_LEGS: tuple[str, ...] = ("FR", "FL", "RR", "RL")
_PARTS = ("hip", "thigh", "calf")
#: Actuated joints in the URDF order (FL, FR, RL, RR) x (hip, thigh, calf).
JOINT_NAMES: tuple[str, ...] = tuple(f"{leg}_{part}_joint" for leg in LEGS for part in _PARTS)
#: The same joints in the Unitree SDK's motor order.
UNITREE_SDK_JOINT_NAMES: tuple[str, ...] = tuple(
    f"{leg}_{part}_joint" for leg in UNITREE_SDK_LEGS for part in _PARTS
)
#: Foot frame of each leg: the centre of the foot sphere.
FOOT_FRAMES: dict[str, str] = {leg: f"{leg}_foot" for leg in LEGS}
#: Radius of the GO2 foot sphere [m] (the foot frames stand this high on flat ground).
FOOT_RADIUS_M = 0.022

_DISTRIBUTION = "example-robot-data"
_ROBOT_DIR = "share/example-robot-data/robots/go2_description"
_NQ, _NV, _NJ = 19, 18, 12


def _find_go2_folder() -> Path:
    """Locate ``go2_description`` inside the installed example-robot-data distribution."""
    try:
        dist = importlib.metadata.distribution(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError as err:
        raise DescriptionNotFoundError(
            "the GO2 description comes from the Python package 'example-robot-data', which is "
            "not installed: run `pip install example-robot-data==6.0.0` (or `make install`)"
        ) from err
    for entry in dist.files or ():
        path = str(entry).replace("\\", "/")
        if path.endswith(f"{_ROBOT_DIR}/urdf/go2.urdf"):
            urdf = Path(str(dist.locate_file(entry)))
            if urdf.is_file():
                return urdf.parent.parent
    raise DescriptionNotFoundError(
        f"'example-robot-data' {dist.version} is installed but has no "
        f"{_ROBOT_DIR}/urdf/go2.urdf: reinstall it with `pip install --force-reinstall "
        "example-robot-data==6.0.0`"
    )


@lru_cache(maxsize=1)
def _installed_go2_folder() -> Path:
    """:func:`_find_go2_folder`, once a process: scanning the distribution's ~1000 files
    takes about 10 ms, and the installed files do not move while the process runs. (A
    failure is not cached: it is raised again, with its advice, on the next call.)"""
    return _find_go2_folder()


@dataclass(frozen=True)
class Go2Description:
    """Where the GO2 files are, and the facts every other module takes from them.

    Joint order everywhere in this library is :data:`JOINT_NAMES` (URDF order); Pinocchio
    configurations are ``q = [x, y, z, qx, qy, qz, qw, joints...]`` (19) and velocities
    ``v = [base linear (base frame), base angular (base frame), joints...]`` (18).
    """

    folder: Path = field(default_factory=_installed_go2_folder)

    @staticmethod
    def default() -> Go2Description:
        """The description of the installed files, one instance a process: its model,
        limits and poses are computed once, for every part that needs them."""
        return _default_description()

    @property
    def urdf_path(self) -> Path:
        """The GO2 URDF file."""
        return self.folder / "urdf" / "go2.urdf"

    @property
    def srdf_path(self) -> Path:
        """The GO2 SRDF file (holds the ``standing`` pose)."""
        return self.folder / "srdf" / "go2.srdf"

    @property
    def package_share_dir(self) -> Path:
        """The ``share/`` folder that resolves ``package://example-robot-data/...`` URIs."""
        return self.folder.parents[2]

    def mesh_uri_prefix(self) -> str:
        """The ``package://`` prefix the URDF uses for its meshes."""
        return "package://example-robot-data/robots/go2_description/"

    def set_ros_package_path(self) -> None:
        """Make ``package://`` URIs resolvable for PlaCo (it reads ``ROS_PACKAGE_PATH``)."""
        share = str(self.package_share_dir)
        paths = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
        if share not in paths:
            os.environ["ROS_PACKAGE_PATH"] = os.pathsep.join([share, *paths])

    def build_model(self) -> pin.Model:
        """A Pinocchio model of the GO2 with a free-flyer base (nq 19, nv 18)."""
        model = pin.buildModelFromUrdf(str(self.urdf_path), pin.JointModelFreeFlyer())
        names = tuple(model.names[2:])
        if names != JOINT_NAMES or model.nq != _NQ or model.nv != _NV:
            raise DescriptionNotFoundError(
                f"{self.urdf_path} is not the expected GO2 model: joints {names}"
            )
        return model

    @cached_property
    def model(self) -> pin.Model:
        """A shared Pinocchio model (build your own with :meth:`build_model` to modify it)."""
        return self.build_model()

    @cached_property
    def position_lower(self) -> np.ndarray:
        """Joint position lower limits [rad], description order."""
        return self.model.lowerPositionLimit[7:].copy()

    @cached_property
    def position_upper(self) -> np.ndarray:
        """Joint position upper limits [rad], description order."""
        return self.model.upperPositionLimit[7:].copy()

    @cached_property
    def velocity_limit(self) -> np.ndarray:
        """Joint velocity limits [rad/s], description order."""
        return self.model.velocityLimit[6:].copy()

    @cached_property
    def effort_limit(self) -> np.ndarray:
        """Joint torque limits [N m], description order."""
        return self.model.effortLimit[6:].copy()

    @cached_property
    def total_mass(self) -> float:
        """Total mass [kg]."""
        return float(pin.computeTotalMass(self.model))

    @cached_property
    def poses(self) -> dict[str, np.ndarray]:
        """Named configurations (Pinocchio convention): ``standing`` (SRDF) and ``lying``."""
        return {"standing": self._srdf_standing(), "lying": self._lying()}

    def pose(self, name: str) -> np.ndarray:
        """A copy of the named configuration (19,), e.g. ``pose("standing")``."""
        check_name("pose", name, self.poses)
        return self.poses[name].copy()

    def _srdf_standing(self) -> np.ndarray:
        root = ET.parse(self.srdf_path).getroot()
        state = next(
            (s for s in root.iter("group_state") if s.get("name") == "standing"), None
        )
        if state is None:
            raise DescriptionNotFoundError(f"{self.srdf_path} has no 'standing' group_state")
        values = {j.get("name"): [float(x) for x in j.get("value", "").split()]
                  for j in state.iter("joint")}
        q = np.empty(_NQ)
        q[:7] = values["root_joint"]
        q[7:] = [values[name][0] for name in JOINT_NAMES]
        return q

    def _lying(self) -> np.ndarray:
        """Legs folded under the body (Unitree's lie-down pose), feet on the ground."""
        q = np.zeros(_NQ)
        q[6] = 1.0
        q[7:] = np.tile([0.0, 1.25, -2.70], 4)
        q[7::3] = [0.1, -0.1, 0.1, -0.1]
        data = self.model.createData()
        pin.framesForwardKinematics(self.model, data, q)
        lowest = min(data.oMf[self.model.getFrameId(f)].translation[2]
                     for f in FOOT_FRAMES.values())
        q[2] = FOOT_RADIUS_M - lowest
        return q

    def joint_index(self, name: str) -> int:
        """Index of an actuated joint in the description order."""
        check_name("joint", name, JOINT_NAMES)
        return JOINT_NAMES.index(name)

    def leg_joint_indices(self, leg: str) -> list[int]:
        """Indices (description order) of a leg's hip, thigh and calf joints."""
        check_name("leg", leg, LEGS)
        return [JOINT_NAMES.index(f"{leg}_{part}_joint") for part in _PARTS]


@lru_cache(maxsize=1)
def _default_description() -> Go2Description:
    return Go2Description()
