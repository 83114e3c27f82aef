"""Rigid-body kinematics and dynamics of a floating-base robot, compiled into one call per tick.

:class:`RobotKinematics` reads the model into records once
(:mod:`wbc.model.kinematics_records`) and runs the compiled algorithms on them
(:mod:`wbc.model.kinematics_kernels`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numba
import numpy as np
import pinocchio as pin

from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_vector
from wbc.model.kinematics_kernels import _DONE, _NOT_FINITE, _update
from wbc.model.kinematics_records import kinematics_records


class RobotKinematics:
    """Kinematics and dynamics of a free-flyer robot with revolute joints, in one compiled call.

    Reads the Pinocchio model once (tree, joint placements, inertias including the fixed
    bodies Pinocchio merged, frames, gravity); each :meth:`compute` then replaces Pinocchio's
    ``computeAllTerms``, ``updateFramePlacements``, ``centerOfMass`` and the per-frame
    Jacobian, velocity and acceleration calls with one compiled call that allocates nothing.
    Pinocchio's conventions: ``q = [base position (world) [m], base quaternion (x, y, z, w),
    joint angles [rad]]``, ``v = [base linear velocity [m/s], base angular velocity [rad/s]
    (both in the base frame), joint rates [rad/s]]``.

    Every output below is an array allocated once and overwritten in place by :meth:`compute`
    (hold a reference, or ``.copy()`` to keep a value); spatial 6-vectors are (linear;
    angular), world-aligned. The compiled code is specialised to the model's sizes and the
    number of frames: the first computation for new sizes compiles (~8 s, then cached on disk).

    Attributes:
        nq, nv: Configuration and velocity sizes.
        frames: Names of the computed frames, in the order of the ``frame_*`` arrays.
        total_mass: Mass of the robot [kg].
        q, v: Copies of the last state (nq,), (nv,).
        mass_matrix: Joint-space inertia ``M`` (nv, nv), symmetric [kg, kg m, kg m^2].
        nonlinear_effects: Coriolis, centrifugal and gravity torques ``C v + g`` (nv,)
            [N, N m] (the base entries are the base-frame wrench).
        gravity_torques: The gravity part ``g`` alone (nv,) [N, N m].
        com_position: World centre of mass (3,) [m].
        com_velocity: Its velocity (3,) [m/s].
        com_drift: Its acceleration at zero ``qdd`` (3,) [m/s^2].
        com_jacobian: ``d com / d v`` (3, nv).
        base_position, base_rotation: World placement of the root joint (3,) [m], (3, 3).
        frame_position, frame_rotation: World placements of the frames (nf, 3) [m],
            (nf, 3, 3).
        frame_jacobian: Jacobians at the frame origins (nf, 6, nv), linear rows [m] then
            angular rows.
        frame_velocity: Velocities of the frame origins (nf, 6) [m/s; rad/s].
        frame_drift: Their classical accelerations at zero ``qdd``, ``dJ/dt v`` (nf, 6)
            [m/s^2; rad/s^2].
    """

    def __init__(self, model: pin.Model, frames: Sequence[str]) -> None:
        """Read the model and allocate every output.

        Args:
            model: A Pinocchio model: an optional free flyer attached to the universe, then
                revolute joints (``JointModelRX/RY/RZ`` or ``JointModelRevoluteUnaligned``).
            frames: Names of the model frames to compute.

        Raises:
            ConfigurationError: An unsupported joint (named, with its type), or a frame name
                the model does not have (the message lists the valid ones).
        """
        self.frames: tuple[str, ...] = tuple(frames)
        self.nq: int = model.nq
        self.nv: int = model.nv
        self._model, self._data = kinematics_records(model, self.frames)
        record = self._data[0]  # a view: its fields are views of the data record
        self.total_mass: float = float(self._model["total_mass"][0])
        self.q: np.ndarray = record["q"]
        self.v: np.ndarray = record["v"]
        self.mass_matrix: np.ndarray = record["mass_matrix"]
        self.nonlinear_effects: np.ndarray = record["nonlinear_effects"]
        self.gravity_torques: np.ndarray = record["gravity_torques"]
        self.com_position: np.ndarray = record["com_position"]
        self.com_velocity: np.ndarray = record["com_velocity"]
        self.com_drift: np.ndarray = record["com_drift"]
        self.com_jacobian: np.ndarray = record["com_jacobian"]
        self.base_rotation: np.ndarray = record["joint_rotation"][1]
        self.base_position: np.ndarray = record["joint_translation"][1]
        self.frame_rotation: np.ndarray = record["frame_rotation"]
        self.frame_position: np.ndarray = record["frame_position"]
        self.frame_jacobian: np.ndarray = record["frame_jacobian"]
        self.frame_velocity: np.ndarray = record["frame_velocity"]
        self.frame_drift: np.ndarray = record["frame_drift"]
        vector = numba.types.Array(numba.float64, 1, "A", readonly=True)
        # The compiled overload for float64 vectors: called without the dispatcher's typing
        # of the two record arrays (half a microsecond a call).
        self._update_vectors = _update.compile((vector, vector, numba.typeof(self._model),
                                                numba.typeof(self._data)))

    def frame_index(self, name: str) -> int:
        """Index of frame ``name`` in the ``frame_*`` arrays.

        Raises:
            ConfigurationError: ``name`` is not one of :attr:`frames` (they are listed).
        """
        if name not in self.frames:
            raise ConfigurationError(f"frame: {name!r} is not computed; computed frames: "
                                     f"{list(self.frames)}")
        return self.frames.index(name)

    def compute(self, q: np.ndarray, v: np.ndarray) -> bool:
        """Recompute every output at the state ``(q, v)``: one compiled call, no allocation.

        The hot-path entry: ``q`` and ``v`` must be float64 NumPy arrays; their sizes and
        finiteness are checked in the compiled call. Use :meth:`checked_compute` for other
        inputs (lists, other dtypes) or to have a non-finite value raise.

        Args:
            q: Configuration (nq,): base position [m], quaternion (x, y, z, w), joints [rad].
            v: Velocity (nv,): base linear [m/s] and angular [rad/s] in the base frame,
                joint rates [rad/s].

        Returns:
            True; False, leaving every output (``q`` and ``v`` included) as it was, when
            ``q`` or ``v`` holds a NaN or an infinite value.

        Raises:
            ConfigurationError: ``q`` or ``v`` has the wrong size.
        """
        status = _update(q, v, self._model, self._data)
        if status == _DONE:
            return True
        if status == _NOT_FINITE:
            return False
        raise ConfigurationError(
            f"RobotKinematics.compute: expected q of shape ({self.nq},) and v of shape "
            f"({self.nv},), received {np.shape(q)} and {np.shape(v)}")

    def compute_vectors(self, q: np.ndarray, v: np.ndarray) -> bool:
        """:meth:`compute` for inputs the caller has made float64 NumPy vectors (1-D), as
        the controller's tick does: the compiled call without numba's typing of its
        arguments. Anything else (another dtype, a list, a matrix) is the caller's error:
        use :meth:`compute`."""
        status = self._update_vectors(q, v, self._model, self._data)
        if status == _DONE:
            return True
        if status == _NOT_FINITE:
            return False
        return self.compute(q, v)  # raises, naming the sizes

    def checked_compute(self, q: np.ndarray, v: np.ndarray) -> None:
        """:meth:`compute` after converting and validating the inputs (off the hot path).

        Raises:
            ConfigurationError: Not numeric, or the wrong shape.
            NonFiniteError: A NaN or infinite entry.
        """
        self.compute(as_vector("q", q, self.nq), as_vector("v", v, self.nv))
