"""Base class of the QP's tasks: ``weight * ||J x + drift - desired||^2`` on chosen variables."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, cast

import numba
import numpy as np

from tasks.task_block import InPlace, TaskBlock
from tasks.variable_layout import QDD, variable_width
from wbc.core.compiled_call import bind_compiled
from wbc.core.errors import ConfigurationError
from wbc.core.validation import as_float, as_vector

if TYPE_CHECKING:
    from wbc.model.kinematics import RobotKinematics


@numba.njit("b1(f8[:, ::1], f8[:], f8[:], f8[:])", cache=True)
def _store_motion(reference, target, velocity, feedforward):  # pragma: no cover - compiled
    """Copy the three vectors into the rows of ``reference`` (3, dim) if each has ``dim``
    finite entries; whether it did (nothing is written when not)."""
    n = reference.shape[1]
    if target.size != n or velocity.size != n or feedforward.size != n:
        return False
    for i in range(n):
        if not (math.isfinite(target[i]) and math.isfinite(velocity[i])
                and math.isfinite(feedforward[i])):
            return False
    for i in range(n):
        reference[0, i] = target[i]
        reference[1, i] = velocity[i]
        reference[2, i] = feedforward[i]
    return True


class Task:
    """A term of the QP's cost, by default on the generalized accelerations ``qdd`` (nv,).

    Each tick, :meth:`evaluate` reads the robot's kinematics (a
    :class:`tasks.RobotKinematics` already updated at the measured state) and fills, in
    place:

    - ``error`` (dim,): target minus current value, in the task space;
    - ``error_rate`` (dim,): target velocity minus current velocity;
    - ``jacobian`` (dim, width): the task velocity is ``jacobian @ v`` for a task on ``qdd``;
    - ``drift`` (dim,): the task acceleration at ``qdd = 0`` (``Jdot v``);
    - ``desired_acceleration`` (dim,): ``kp * error + kd * error_rate + feedforward``.

    The QP term is ``weight * row_weights * (jacobian @ x_vars + drift - desired)^2``,
    summed over the rows, where ``x_vars`` are the decision variables the task names in
    ``variables`` (:class:`tasks.VariableLayout`): ``"qdd"`` (the default, nv columns),
    ``"force:<contact>"`` (3 columns, world x, y, z [N]; a contact in the air has none and
    its force counts as zero), ``"slack:<name>"``. Gains default to critical damping,
    ``kd = 2 sqrt(kp)``.

    To write a task, subclass this, set ``dim``, list the frames it reads in ``frames``
    and implement :meth:`compute`. Write into the arrays in place (``array[...] = ...``):
    a problem builder that registers the task hands it a :class:`tasks.TaskBlock` of views
    into the QP's stacked rows (:meth:`attach`), and replacing an array (``self.jacobian =
    ...``, ``task.row_weights = ...``) raises, naming the task and the array. The built-in
    tasks override :meth:`_compiled_call` with one compiled kernel.

    The references live in ``reference`` (3, dim): target, target velocity, feed-forward
    acceleration; the gains in ``gains``: kp, kd, weight. Both are updated in place (setters
    copy their arguments in), so compiled code can read them without copies.
    """

    #: Number of task rows.
    dim: int = 0
    #: Names of the frames whose kinematics the task reads (``RobotKinematics.frames``).
    frames: tuple[str, ...] = ()
    #: The decision variables the Jacobian's columns span, in order.
    variables: tuple[str, ...] = (QDD,)

    jacobian = InPlace("jacobian")
    drift = InPlace("drift")
    desired_acceleration = InPlace("desired")
    #: Per-row multipliers of ``weight`` (ones by default).
    row_weights = InPlace("row_weights")
    gains = InPlace("gains")
    error = InPlace()
    error_rate = InPlace()
    reference = InPlace()

    def __init__(self, *, kp: float, kd: float | None = None, weight: float = 1.0,
                 nv: int | None = None):
        """Args:
            kp: Stiffness [1/s^2].
            kd: Damping [1/s]; ``None`` for critical damping ``2 sqrt(kp)``.
            weight: Cost weight (dimensionless, relative to other tasks).
            nv: Dimension of the velocity vector; ``None``: that of the kinematics the task
                is first bound to (:meth:`bind`), which allocates the Jacobian.
        """
        self.nv = nv
        own = self.__dict__
        own["_reference"] = np.zeros((3, self.dim))
        own["_error"] = np.zeros(self.dim)
        own["_error_rate"] = np.zeros(self.dim)
        self._block = TaskBlock.owned(self.dim, 0 if nv is None else self.width(nv))
        if nv is not None:
            self.setup(self._block)
        self._zeros = np.zeros(self.dim)  # the default velocity and feed-forward; never written
        self._has_target = False
        self._kinematics: RobotKinematics | None = None
        self.set_gains(kp=kp, kd=kd)
        self.set_weight(weight)
        #: Indices of ``frames`` in the kinematics, set by :meth:`bind`.
        self.frame_indices = np.zeros(len(self.frames), dtype=np.int64)

    def width(self, nv: int) -> int:
        """Number of Jacobian columns: the widths of ``variables`` for a robot of ``nv``."""
        return sum(variable_width(name, nv) for name in self.variables)

    @property
    def block(self) -> TaskBlock:
        """The arrays the QP's cost reads (views of a problem builder's rows once registered)."""
        return self._block

    @property
    def kp(self) -> float:
        """Stiffness [1/s^2]."""
        return float(self.gains[0])

    @property
    def kd(self) -> float:
        """Damping [1/s]."""
        return float(self.gains[1])

    @property
    def weight(self) -> float:
        """Cost weight."""
        return float(self.gains[2])

    @property
    def target(self) -> np.ndarray | None:
        """A copy of the target (``None`` until set)."""
        return self.reference[0].copy() if self._has_target else None

    @property
    def target_velocity(self) -> np.ndarray:
        """A copy of the target velocity."""
        return self.reference[1].copy()

    @property
    def feedforward(self) -> np.ndarray:
        """A copy of the feed-forward acceleration."""
        return self.reference[2].copy()

    def set_gains(self, *, kp: float, kd: float | None = None) -> None:
        """Set stiffness ``kp`` [1/s^2] and damping ``kd`` [1/s] (critical when ``None``)."""
        kp = as_float("kp", kp, low=0.0)
        kd = 2.0 * math.sqrt(kp) if kd is None else as_float("kd", kd, low=0.0)
        self.gains[0], self.gains[1] = kp, kd

    def set_weight(self, weight: float) -> None:
        """Set the cost weight (>= 0; 0 takes the task out of the QP)."""
        self.gains[2] = as_float("weight", weight, low=0.0)

    def set_row_weights(self, weights: np.ndarray) -> None:
        """Per-row multipliers (dim,) of the weight, each >= 0; copied in."""
        self._check_and_store_row_weights(f"{type(self).__name__}.row_weights", weights)

    def _check_and_store_row_weights(self, name: str, weights: np.ndarray) -> None:
        weights = as_vector(name, weights, self.dim)
        if np.any(weights < 0.0):
            raise ConfigurationError(f"{name}: expected values >= 0, received {weights.tolist()}")
        self.row_weights[:] = weights

    def set_feedforward(self, acceleration: np.ndarray) -> None:
        """Set the feed-forward task acceleration (dim,)."""
        self.reference[2] = as_vector(f"{type(self).__name__}.feedforward", acceleration,
                                      self.dim)

    def set_motion(self, target: np.ndarray, velocity: np.ndarray | None = None,
                   feedforward: np.ndarray | None = None) -> None:
        """Set the target, its velocity and the feed-forward acceleration together.

        For a reference that moves every tick (a trajectory): float64 vectors of ``dim``
        finite entries are checked and copied in one compiled call; anything else is
        converted and validated as :meth:`set_target` does. ``None`` is zero. A rejected
        value leaves all three as they were.
        """
        self._set_reference(self._field(), target, velocity, self._zeros
                            if feedforward is None else feedforward)

    def _field(self) -> str:
        """The name error messages give this task's references."""
        return type(self).__name__

    def _set_reference(self, name: str, target: np.ndarray, velocity: np.ndarray | None,
                       feedforward: np.ndarray | None = None) -> None:
        """Validate, then store the target, its velocity (``None``: zero) and, when given,
        the feed-forward; a rejected value leaves all of them as they were."""
        reference = self.reference
        if velocity is None:
            velocity = self._zeros
        if feedforward is None:
            feedforward = reference[2]  # kept: copied onto itself
        try:
            if _store_motion(reference, target, velocity, feedforward):
                self._has_target = True
                return
        except TypeError:  # not float64 vectors: converted below
            pass
        target = as_vector(f"{name}.target", target, self.dim)
        velocity = as_vector(f"{name}.target_velocity", velocity, self.dim)
        feedforward = as_vector(f"{name}.feedforward", feedforward, self.dim)
        reference[0], reference[1], reference[2] = target, velocity, feedforward
        self._has_target = True

    # ------------------------------------------------------------------ blocks

    def setup(self, block: TaskBlock) -> None:
        """Write the entries that never change (a selection Jacobian) into a new block of
        the task's own; nothing by default. A block a builder attaches gets them copied."""

    def bind(self, kinematics: RobotKinematics) -> None:
        """Size the Jacobian for ``kinematics``' robot and resolve ``frames`` in it (a
        controller does it when it registers the task).

        Raises:
            ConfigurationError: A robot of another size than ``nv``, an unknown variable, or
                a frame the kinematics does not compute.
        """
        if self.nv is not None and self.nv != kinematics.nv:
            raise ConfigurationError(f"task: {type(self).__name__} has nv={self.nv}, the robot "
                                     f"has nv={kinematics.nv}")
        self.nv = kinematics.nv
        width = self.width(kinematics.nv)
        if self._block.jacobian.shape != (self.dim, width):
            block = TaskBlock.owned(self.dim, width)
            self._block.copy_into(block)
            self.setup(block)
            self._block = block
            self._call = None
        for i, frame in enumerate(self.frames):
            self.frame_indices[i] = kinematics.frame_index(frame)
        self._kinematics = kinematics

    def attach(self, block: TaskBlock) -> None:
        """Use ``block`` from now on (a problem builder's views), with this task's values
        (gains, row weights, constant Jacobian entries) copied into it. Bind first.

        Raises:
            ConfigurationError: A block of another shape than the task's arrays.
        """
        expected = self._block.jacobian.shape
        if block.jacobian.shape != expected or block.gains.shape != (3,):
            raise ConfigurationError(
                f"{type(self).__name__}: a task block of Jacobian shape {expected} expected, "
                f"received {block.jacobian.shape}; bind the task to the kinematics first")
        self._block.copy_into(block)
        self._block = block
        self._call = None  # its compiled call held the arrays it had before

    def detach(self) -> None:
        """Go back to arrays of its own, with its values (a builder that drops the task)."""
        block = TaskBlock.owned(self.dim, self._block.jacobian.shape[1])
        self._block.copy_into(block)
        self._block = block
        self._call = None

    # ------------------------------------------------------------------ the tick

    def evaluate(self, kinematics: RobotKinematics) -> None:
        """Recompute error, Jacobian, drift and desired acceleration at the last state.

        A built-in task runs its compiled kernel, whose arguments are gathered once
        (:meth:`_compiled_call`) and again only when its arrays or the kinematics change;
        any other task runs :meth:`compute` and the PD law in NumPy.
        """
        call = self._call
        if call is None or call[0] is not kinematics:
            if kinematics is not self._kinematics:
                self.bind(kinematics)
            if not self._bind(kinematics):
                self.compute(kinematics)
                desired = self.desired_acceleration
                desired[:] = self.gains[0] * self.error + self.gains[1] * self.error_rate
                desired += self.reference[2]
                return
            call = cast("tuple[Any, ...]", self._call)  # _bind set it
        call[1]()

    def prepare(self, kinematics: RobotKinematics) -> None:
        """Bind the compiled kernel to this task's arrays now, which loads its compiled code
        (milliseconds for a kernel's first call in a process), rather than on the first
        tick that runs the task. Nothing for a task written in Python, or one that cannot
        run yet (no target): that one binds on its first tick."""
        if kinematics is not self._kinematics:
            self.bind(kinematics)
        call = self._call
        if call is None or call[0] is not kinematics:
            try:
                self._bind(kinematics)
            except ConfigurationError:  # no target yet
                pass

    def _bind(self, kinematics: RobotKinematics) -> bool:
        """Bind the compiled kernel (``_call``); False for a task written in Python."""
        compiled = self._compiled_call(kinematics)
        if compiled is None:
            return False
        self._call = (kinematics, bind_compiled(compiled[0], *compiled[1]))
        return True

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple | None:
        """``(kernel, arguments)`` that fill this task's arrays, or ``None`` (use compute).

        Called when the arrays were re-bound (``_call`` reset to ``None``); raises when the
        task cannot run yet (no target).
        """
        return None

    #: The cached ``(kinematics, bound kernel)`` of a compiled task (see
    #: :func:`wbc.core.compiled_call.bind_compiled`).
    _call: tuple | None = None

    def compute(self, kinematics: RobotKinematics) -> None:
        """Fill ``error``, ``error_rate``, ``jacobian`` and ``drift``; subclasses implement."""
        raise NotImplementedError(f"{type(self).__name__}.compute")

    def _require_target(self) -> np.ndarray:
        """The target (the internal array), or a clear error when it was never set."""
        if not self._has_target:
            raise ConfigurationError(
                f"{type(self).__name__}: target not set; call set_target(...) first"
            )
        return self.reference[0]
