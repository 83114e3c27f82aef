"""Add a task of your own to the whole-body QP: a base-height task, written in NumPy, and
the same task with a compiled kernel (which the tick runs inside its one compiled call).

Run ``python examples/custom_task.py``: the GO2 stands on the default (realistic) MuJoCo
plant and raises its base by 4 cm in one second, by a task this file defines, while the
built-in centre-of-mass task keeps the CoM over the feet on x and y.
"""

from __future__ import annotations

import numba

from sim.control_loop import ControlLoop
from tasks import RobotKinematics, Task
from wbc import WholeBodyController


class BaseHeightTask(Task):
    """Track the height [m] of the base frame's origin above the ground (world z)."""

    dim = 1
    frames = ("base",)   # the frames whose kinematics compute() reads

    def __init__(self, *, kp: float = 100.0, weight: float = 200.0):
        super().__init__(kp=kp, weight=weight)

    def set_target(self, height_m: float, velocity_m_s: float = 0.0) -> None:
        """Target height [m] and vertical velocity [m/s]."""
        self._set_reference("BaseHeightTask", [height_m], [velocity_m_s])

    def compute(self, kinematics: RobotKinematics) -> None:
        # Write in place: these are views of the task's block of the QP (replacing one raises).
        i = self.frame_indices[0]
        self.error[0] = self.reference[0, 0] - kinematics.frame_position[i, 2]
        self.error_rate[0] = self.reference[1, 0] - kinematics.frame_velocity[i, 2]
        self.jacobian[0] = kinematics.frame_jacobian[i, 2]
        self.drift[0] = kinematics.frame_drift[i, 2]


# No disk cache: numba cannot reload a cached function from a module imported by its path
# (as the tests import this file); the tick's program that calls it is cached all the same.
@numba.njit
def base_height_rows(frame_position, frame_velocity, frame_jacobian, frame_drift, index,
                     reference, gains, error, error_rate, jacobian, drift, desired):
    """What :meth:`BaseHeightTask.compute` writes, and the PD law, in compiled code."""
    error[0] = reference[0, 0] - frame_position[index, 2]
    error_rate[0] = reference[1, 0] - frame_velocity[index, 2]
    jacobian[0, :] = frame_jacobian[index, 2, :]
    drift[0] = frame_drift[index, 2]
    desired[0] = gains[0] * error[0] + gains[1] * error_rate[0] + reference[2, 0]


class CompiledBaseHeightTask(BaseHeightTask):
    """:class:`BaseHeightTask` with a kernel: ``_compiled_call`` returns it and every
    argument (arrays updated in place; the task's arrays are views of the QP's rows), and
    the controller runs it inside the tick's one compiled call, as it runs the built-in
    tasks' kernels."""

    def _compiled_call(self, kinematics: RobotKinematics) -> tuple:
        k = kinematics
        return base_height_rows, (
            k.frame_position, k.frame_velocity, k.frame_jacobian, k.frame_drift,
            int(self.frame_indices[0]), self.reference, self.gains, self.error,
            self.error_rate, self.jacobian, self.drift, self.desired_acceleration)


def run(*, raise_m: float = 0.04, ramp_s: float = 1.0, settle_s: float = 1.0,
        with_task: bool = True, compiled: bool = False) -> dict[str, float]:
    """Stand, raise the base by ``raise_m`` over ``ramp_s``, hold ``settle_s``; returns a
    summary: start and end base height [m] (the simulator's truth), target [m], QP
    failures, worst violation. ``compiled``: the task with its kernel.

    The controller reads the state estimated from the simulated GO2's sensors, as it would
    on a robot; the loop's pieces are driven by hand: read, step, write.
    """
    controller = WholeBodyController()
    height = CompiledBaseHeightTask() if compiled else BaseHeightTask()
    if with_task:
        controller.add_task(height)
        controller.com_task.row_weights[2] = 0.0   # the CoM height is the new task's job
    loop = ControlLoop.simulated(controller=controller)   # resets the controller
    q, v = loop.read_state()
    start = float(q[2])
    true_start = float(loop.true_state()[0][2])
    height.set_target(start)
    failures, violation = 0, 0.0
    ticks = round((ramp_s + settle_s) / controller.control_period_s)
    for k in range(ticks):
        t = k * controller.control_period_s
        s = min(t / ramp_s, 1.0)
        # A smooth (cubic) ramp of the target, with its velocity.
        height.set_target(start + raise_m * (3 * s**2 - 2 * s**3),
                          raise_m * 6 * s * (1 - s) / ramp_s)
        out = controller.step(q, v)
        failures += not out.ok
        violation = max(violation, *controller.problem.violations(controller.last_solution))
        loop.robot.write_command(out)
        q, v = loop.read_state()
    return {"start_m": true_start, "end_m": float(loop.true_state()[0][2]),
            "target_m": true_start + raise_m, "failures": failures,
            "max_violation": violation}


if __name__ == "__main__":
    summary = run()
    print(f"base height {summary['start_m']:.4f} m -> {summary['end_m']:.4f} m "
          f"(target {summary['target_m']:.4f} m); QP failures {summary['failures']}, "
          f"worst constraint violation {summary['max_violation']:.1e}")
