"""TSID, the reference C++ whole-body QP library, timed on the GO2 problem of the benchmark.

Run by :mod:`benchmarks.tsid_row` with the Python of a separate environment that has ``tsid``
(``make tsid`` builds it: the registry has TSID's bindings but only the source of ``libtsid``,
built against its own Pinocchio, which the project's environment cannot share). This file
imports nothing of the project, only NumPy, Pinocchio and TSID:

    python benchmarks/tsid_peer.py problem.npz result.json

``problem.npz`` holds the robot (URDF path, package directory, frame and joint names), the
controller's gains, weights and limits, and, for every tick, the state the project's
controller read and every reference it held (the CoM, base yaw, posture, foot targets and
weights, each foot's normal-force bounds). TSID builds the same tasks (``InverseDynamics
FormulationAccForce``: CoM, base orientation, posture and swing-foot equality tasks, weighted
like the project's; one ``ContactPoint`` a stance foot, friction coefficient and normal-force
bounds; actuation bounds) and solves them with its ``SolverHQuadProgFast`` (eiquadprog).

Timed per tick, as the project's ``step`` is: ``computeProblemData``, ``solve`` and reading
the torques (``getActuatorForces``). Setting the references before the tick, and adding or
removing a contact when a foot lifts or lands, are not timed (a few ticks a lift).
"""

from __future__ import annotations

import json
import sys
import time
from importlib.metadata import version

import numpy as np
import pinocchio as pin
import tsid


def _sample(position: np.ndarray, velocity: np.ndarray, acceleration: np.ndarray
            ) -> tsid.TrajectorySample:
    sample = tsid.TrajectorySample(len(position), len(velocity))
    sample.value(np.asarray(position, float))
    sample.derivative(np.asarray(velocity, float))
    sample.second_derivative(np.asarray(acceleration, float))
    return sample


def _se3_sample(rotation: np.ndarray, position: np.ndarray, velocity: np.ndarray,
                acceleration: np.ndarray) -> tsid.TrajectorySample:
    """A frame reference: TSID's SE3 samples are 12 numbers (translation, then the rotation
    matrix by columns) and 6-vector velocities (linear first)."""
    pos = np.concatenate([position, rotation.reshape(-1, order="F")])
    vel = np.concatenate([velocity, np.zeros(3)])
    acc = np.concatenate([acceleration, np.zeros(3)])
    return _sample(pos, vel, acc)


class TsidGo2:
    """The benchmark's balance problem in TSID."""

    def __init__(self, p: dict[str, np.ndarray]):
        self.p = p
        self.robot = robot = tsid.RobotWrapper(str(p["urdf"]), [str(p["package_dir"])],
                                               pin.JointModelFreeFlyer(), False)
        model = robot.model()
        names = [model.names[i] for i in range(2, model.njoints)]
        if names != list(p["joint_names"]):
            raise SystemExit(f"TSID's joint order {names} is not the project's "
                             f"{list(p['joint_names'])}")
        q0, v0 = p["q"][0], p["v"][0]
        self.formulation = form = tsid.InverseDynamicsFormulationAccForce("go2", robot, False)
        form.computeProblemData(0.0, q0, v0)
        data = form.data()

        def gains(task: object, kp: float, n: int) -> None:
            task.setKp(kp * np.ones(n))
            task.setKd(2.0 * np.sqrt(kp) * np.ones(n))

        self.com = tsid.TaskComEquality("com", robot)
        gains(self.com, float(p["com_kp"]), 3)
        form.addMotionTask(self.com, float(p["com_weight"]), 1, 0.0)
        self.base = tsid.TaskSE3Equality("base", robot, "base")
        self.base.setMask(np.array([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]))
        gains(self.base, float(p["base_orientation_kp"]), 6)
        form.addMotionTask(self.base, float(p["base_orientation_weight"]), 1, 0.0)
        self.posture = tsid.TaskJointPosture("posture", robot)
        gains(self.posture, float(p["posture_kp"]), 12)
        form.addMotionTask(self.posture, float(p["posture_weight"]), 1, 0.0)
        self.torque = tsid.TaskActuationBounds("torque", robot)
        self.torque.setBounds(-p["tau_max"], p["tau_max"])
        form.addActuationTask(self.torque, 1.0, 0, 0.0)

        self.contacts: dict[str, tsid.ContactPoint] = {}
        self.feet: dict[str, tsid.TaskSE3Equality] = {}
        self.frames = [str(f) for f in p["foot_frames"]]
        for frame in self.frames:
            contact = tsid.ContactPoint(f"contact {frame}", robot, frame,
                                        np.array([0.0, 0.0, 1.0]),
                                        float(p["friction_coefficient"]),
                                        float(p["min_normal_force_n"]),
                                        float(p["max_normal_force_n"]))
            contact.useLocalFrame(False)
            contact.setKp(np.zeros(3))
            contact.setKd(float(p["contact_damping"]) * np.ones(3))
            contact.setReference(robot.framePosition(data, model.getFrameId(frame)))
            self.contacts[frame] = contact
            foot = tsid.TaskSE3Equality(f"foot {frame}", robot, frame)
            foot.setMask(np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))
            foot.useLocalFrame(False)
            gains(foot, float(p["foot_kp"]), 6)
            self.feet[frame] = foot
        self.stance = [False] * len(self.frames)
        #: The weight of each foot's tracking task in the formulation (0: not in it).
        self.foot_weight = [0.0] * len(self.frames)
        self.solver = tsid.SolverHQuadProgFast("eiquadprog")

    def set_references(self, k: int) -> None:
        """The references the project's controller held at tick ``k``; contacts on or off."""
        p, form, data = self.p, self.formulation, self.formulation.data()
        self.com.setReference(_sample(p["com_p"][k], p["com_v"][k], p["com_a"][k]))
        self.base.setReference(_se3_sample(p["base_rotation"][k], np.zeros(3), np.zeros(3),
                                           np.zeros(3)))
        self.posture.setReference(_sample(p["posture_p"][k], p["posture_v"][k],
                                          p["posture_a"][k]))
        resized = False
        for i, frame in enumerate(self.frames):
            bound = float(p["force_bounds"][k, i])
            stance = bool(p["stance"][k, i])
            if stance != self.stance[i]:
                resized = True
                if stance:
                    self._set_foot_task(i, 0.0)
                    model = self.robot.model()
                    self.contacts[frame].setReference(
                        self.robot.framePosition(data, model.getFrameId(frame)))
                    form.addRigidContact(self.contacts[frame], float(p["force_weight"]), 1.0, 1)
                else:
                    form.removeRigidContact(f"contact {frame}", 0.0)
                self.stance[i] = stance
            if stance:
                contact = self.contacts[frame]
                # TSID checks 0 < min <= max on each call: lower the minimum first.
                contact.setMinNormalForce(1e-9)
                contact.setMaxNormalForce(max(bound, 1e-6))
                contact.setMinNormalForce(max(min(float(p["min_normal_force_n"]), bound), 1e-9))
            else:
                resized |= self._set_foot_task(i, float(p["foot_weight"][k, i]))
                self.feet[frame].setReference(_se3_sample(
                    np.eye(3), p["foot_p"][k, i], p["foot_v"][k, i], p["foot_a"][k, i]))
        if resized or k == 0:
            self.solver.resize(form.nVar, form.nEq, form.nIn)

    def _set_foot_task(self, i: int, weight: float) -> bool:
        """Put foot ``i``'s tracking task in the formulation at ``weight`` (0: out of it);
        True when the formulation changed."""
        if weight == self.foot_weight[i]:
            return False
        frame = self.frames[i]
        if self.foot_weight[i] > 0.0:
            self.formulation.removeTask(f"foot {frame}", 0.0)
        if weight > 0.0:
            self.formulation.addMotionTask(self.feet[frame], weight, 1, 0.0)
        self.foot_weight[i] = weight
        return True

    def tick(self, k: int) -> tuple[float, np.ndarray, float]:
        """One timed tick: (seconds, joint torques, total normal force [N])."""
        q, v = self.p["q"][k], self.p["v"][k]
        start = time.perf_counter()
        problem = self.formulation.computeProblemData(float(self.p["t"][k]), q, v)
        solution = self.solver.solve(problem)
        tau = self.formulation.getActuatorForces(solution)
        seconds = time.perf_counter() - start
        if solution.status != 0:
            return seconds, np.full(12, np.nan), np.nan
        normal = sum(self.formulation.getContactForce(f"contact {frame}", solution)[2]
                     for frame, stance in zip(self.frames, self.stance) if stance)
        return seconds, np.asarray(tau, float), float(normal)


def main(problem_path: str, result_path: str) -> None:
    with np.load(problem_path, allow_pickle=False) as archive:
        p = {key: archive[key] for key in archive.files}
    peer = TsidGo2(p)
    ticks = len(p["t"])
    seconds = np.empty(ticks)
    torques = np.empty((ticks, 12))
    normal = np.empty(ticks)
    for k in range(ticks):
        peer.set_references(k)
        seconds[k], torques[k], normal[k] = peer.tick(k)
    json.dump({"seconds": seconds.tolist(), "torques": torques.tolist(),
               "normal_force_n": normal.tolist(), "tsid_version": version("tsid"),
               "pinocchio_version": pin.__version__}, open(result_path, "w"))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        raise SystemExit("usage: python benchmarks/tsid_peer.py PROBLEM.npz RESULT.json")
    main(sys.argv[1], sys.argv[2])
