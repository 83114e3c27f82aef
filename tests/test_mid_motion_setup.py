"""Closed loop: no tick loads compiled code or builds a QP layout, from the first one on.

A numba function's first call in a process reads its machine code from numba's cache
(milliseconds), binding a kernel to new arrays types each of them, and DAQP's structures
for a new QP take a few hundred microseconds: done inside a tick, at the moment a foot
leaves or touches the ground, any of these stalls the 1 kHz loop for several periods. The
loop's construction does them all; this test counts them (it does not time anything) from
the loop's first tick on, while the GO2 stands and runs every behaviour. It runs in a fresh
interpreter: in the test process, earlier tests have already loaded every kernel.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

SCRIPT = r"""
import json
from numba.core import dispatcher
from actions import (FollowJointTrajectoryGoal, HighFiveGoal, JointTrajectory,
                     JointTrajectoryPoint, SitGoal, StandGoal)
from sim.control_loop import ControlLoop
from wbc.backends.daqp_backend import DaqpBackend

loop = ControlLoop.simulated()
events = []
compile_ = dispatcher.Dispatcher.compile
setup = DaqpBackend.setup
goal_name = [""]

def counted_compile(self, sig):
    new = tuple(sig) not in self.overloads
    events.append((goal_name[0], round(loop.robot.time_s, 3), "load" if new else "bind",
                   self.py_func.__qualname__))
    return compile_(self, sig)

def counted_setup(self, problem):
    events.append((goal_name[0], round(loop.robot.time_s, 3), "daqp setup", str(problem.n)))
    return setup(self, problem)

dispatcher.Dispatcher.compile = counted_compile
DaqpBackend.setup = counted_setup
goal_name[0] = "standing"  # the loop's first ticks
loop.spin_for(0.3)
trajectory = JointTrajectory(
    joint_names=["FR_hip_joint", "FR_thigh_joint", "FR_calf_joint"],
    points=[JointTrajectoryPoint(positions=[-0.1, 0.2, -1.6], time_from_start=1.0)])
results = {}
for name, goal in (("high_five", HighFiveGoal(target_height=0.4, hold_seconds=0)),
                   ("follow_joint_trajectory", FollowJointTrajectoryGoal(trajectory=trajectory)),
                   ("sit", SitGoal()), ("stand", StandGoal())):
    goal_name[0] = name
    result = loop.client(name).send_goal_and_wait(goal)
    results[name] = result.status.name
print(json.dumps({"results": results, "events": events}))
"""


def test_no_tick_loads_compiled_code_or_builds_a_qp_layout():
    root = Path(__file__).resolve().parents[1]
    run = subprocess.run([sys.executable, "-c", SCRIPT], cwd=root, capture_output=True,
                         text=True, timeout=600, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert report["results"] == {"high_five": "SUCCEEDED", "follow_joint_trajectory": "SUCCEEDED",
                                 "sit": "SUCCEEDED", "stand": "SUCCEEDED"}
    assert report["events"] == []
