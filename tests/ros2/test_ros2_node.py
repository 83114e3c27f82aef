"""``go2-wbc ros2``, the simulated GO2 as a ROS 2 node, driven by clients written as the ROS 2
tutorials write them, each in its own process; one node process serves the whole module (its
truth report, written when it stops, judges the goals on the simulator's truth).

The tests run in file order and share the node: a high five (with a second goal sent while it
runs), a cancel 2.5 s after acceptance, a goal of 2.0 m, a one-joint FollowJointTrajectory, a
Stand on a remapped name through ``send-goal --ros2``; the last test stops the node and checks
the truth report and the topics recorded meanwhile.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from actions.go2.trajectory_plan import DEFAULT_GOAL_TOLERANCE_RAD
from benchmarks.dds_processes import DdsProcesses, ManagedProcess, wait_until
from tests.ros2.conftest import TopicRecorder, client_argv
from wbc.model.description import JOINT_NAMES

#: The high five's phases in their order (docs/actions.md); "standing" only when it was not.
HIGH_FIVE_PHASES = ["standing", "shifting", "unloading", "raising", "ready", "lowering",
                    "reloading", "shifting_back", "complete"]
#: Longest wait [s] for a client (a loaded 2-core machine: its imports alone can take 10 s).
CLIENT_TIMEOUT_S = 120.0
#: Longest wait [s] for the node to start serving (the kernels are compiled by the install; a
#: kernel edited since, or a loaded machine, makes the first import slow).
NODE_TIMEOUT_S = 600.0
#: The remapping the node is started with.
REMAPPED_STAND = "/robot/stand_up"


class Shared:
    """The node process, its run directory and what the tests leave for the last one."""

    def __init__(self, run: DdsProcesses, node: ManagedProcess, report: Path) -> None:
        self.run = run
        self.node = node
        self.report = report
        self.odom: list[Any] = []
        self.joint_rate_hz = math.nan


@pytest.fixture(scope="module")
def shared(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Shared]:
    workdir = tmp_path_factory.mktemp("ros2_node")
    report = workdir / "truth.json"
    with DdsProcesses(workdir) as run:
        node = run.start("node", "ros2", "--truth-report", str(report),
                         "--ros-args", "--remap", f"stand:={REMAPPED_STAND}")
        node.wait_for_line(r"^ROS 2 node /go2_wbc", timeout_s=NODE_TIMEOUT_S)
        yield Shared(run, node, report)


def start_client(shared: Shared, name: str, script: str, *args: str) -> ManagedProcess:
    """A tutorial client in its own process (its stdout: one JSON line an event)."""
    process = ManagedProcess(name, client_argv(script, *args),
                             output_path=shared.run.path(f"{name}.out"))
    shared.run.processes.append(process)
    return process


def events(process: ManagedProcess) -> list[dict[str, Any]]:
    """The client's JSON lines."""
    return [json.loads(line) for line in process.output().splitlines()
            if line.startswith("{")]


def finish(process: ManagedProcess) -> list[dict[str, Any]]:
    code = process.wait(CLIENT_TIMEOUT_S)
    assert code == 0, process.tail()
    return events(process)


def test_a_high_five_succeeds_and_a_second_goal_meanwhile_is_rejected(
        shared: Shared, recorder: TopicRecorder) -> None:
    recorder.recording = True
    first = start_client(shared, "high_five", "tutorial_high_five_client.py",
                         "--height", "0.4", "--hold", "2", "--ros-args", "-p",
                         "use_sim_time:=true")
    first.wait_for_line(r'"event": "accepted"', timeout_s=CLIENT_TIMEOUT_S)
    second = start_client(shared, "busy", "tutorial_high_five_client.py", "--height", "0.3")
    assert [e["event"] for e in finish(second)] == ["rejected"]
    got = finish(first)
    recorder.recording = False
    kinds = [e["event"] for e in got]
    # ROS 2 orders no topic against a service reply: the first feedback may come first.
    assert kinds.count("accepted") == 1 and kinds[-1] == "result", kinds
    feedback = [e for e in got if e["event"] == "feedback"]
    phases = list(dict.fromkeys(e["phase"] for e in feedback))
    # In order, none skipped (it was standing); the last, "complete", may come after the
    # result, which the tutorial's client does not wait for (ROS 2 orders no topic against a
    # service reply).
    assert phases == HIGH_FIVE_PHASES[1:len(phases) + 1] and len(phases) >= 7, phases
    progress = [e["progress"] for e in feedback]
    assert all(b >= a for a, b in itertools.pairwise(progress))
    result = got[-1]
    assert result["status"] == 4 and result["success"] is True, result  # SUCCEEDED
    assert result["message"].startswith("high five done: foot raised to 0.400 m, held 2 s")
    # The busy robot's reason, in the node's log (ROS 2's goal response carries none).
    assert re.search(r"goal \d+ for 'high_five' rejected \(code \d+\): .*busy",
                     shared.node.output()), shared.node.tail()
    # /joint_states: the 12 joints by their URDF names, at >= 100 Hz: of simulated time
    # always, and of wall time when the simulation kept real time (a machine loaded by other
    # jobs can slow the paced loop below it: then the wall rate is printed, not judged).
    states = recorder.messages["/joint_states"]
    assert len(states) > 100
    assert all(list(m.name) == list(JOINT_NAMES) for _, m in states)
    span_s = states[-1][0] - states[0][0]
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for _, m in states])
    sim_span_s = stamps[-1] - stamps[0]
    shared.joint_rate_hz = (len(states) - 1) / span_s
    real_time_factor = sim_span_s / span_s
    print(f"\n/joint_states: {len(states)} messages in {span_s:.2f} s wall "
          f"({shared.joint_rate_hz:.0f} Hz), {(len(states) - 1) / sim_span_s:.0f} Hz of "
          f"simulated time; real-time factor {real_time_factor:.2f}")
    assert (len(states) - 1) / sim_span_s >= 100.0
    if real_time_factor >= 0.9:
        assert shared.joint_rate_hz >= 100.0
    shared.odom = [m for _, m in recorder.messages["/odom"]]


def test_b_the_same_client_cancels_2_5_s_after_acceptance(shared: Shared) -> None:
    got = finish(start_client(shared, "cancel", "tutorial_high_five_client.py",
                              "--cancel-after", "2.5", "--ros-args", "-p",
                              "use_sim_time:=true"))
    by_kind = {e["event"]: e for e in got}
    assert by_kind["cancel_response"]["goals_canceling"] == 1
    assert by_kind["cancel"]["t"] - by_kind["accepted"]["t"] == pytest.approx(2.5, abs=0.02)
    result = by_kind["result"]
    assert result["status"] == 5 and result["success"] is False, result  # CANCELED
    phases = [e["phase"] for e in got if e["event"] == "feedback"]
    assert phases[-1] == "canceled"


def test_c_a_goal_of_2_m_is_rejected_with_its_reason_logged(shared: Shared) -> None:
    got = finish(start_client(shared, "too_high", "tutorial_high_five_client.py",
                              "--height", "2.0"))
    assert [e["event"] for e in got] == ["rejected"]
    assert re.search(r"rejected \(code \d+\): target_height.*2\.0", shared.node.output()), (
        shared.node.tail())


def test_d_a_one_joint_trajectory_client_moves_fr_calf(shared: Shared,
                                                      recorder: TopicRecorder) -> None:
    target = -1.9
    got = finish(start_client(shared, "trajectory", "tutorial_trajectory_client.py",
                              str(target), "1.0"))
    result = got[-1]
    assert result == {"event": "result", "status": 4, "error_code": 0,
                      "error_string": result["error_string"]}, got[-3:]
    feedback = [e for e in got if e["event"] == "feedback"]
    assert feedback and all(e["joint_names"] == ["FR_calf_joint"] for e in feedback)
    # The leg holds the last point after SUCCEEDED: the joint as /joint_states publishes it.
    recorder.messages["/joint_states"].clear()
    recorder.recording = True
    wait_until(lambda: len(recorder.messages["/joint_states"]) >= 20 or None, timeout_s=30.0,
               what="20 /joint_states messages")
    recorder.recording = False
    calf = JOINT_NAMES.index("FR_calf_joint")
    positions = [m.position[calf] for _, m in recorder.messages["/joint_states"]]
    print(f"\nFR_calf_joint after the goal: {np.mean(positions):.4f} rad (target {target}), "
          f"{len(feedback)} feedback messages received")
    assert max(abs(p - target) for p in positions) <= DEFAULT_GOAL_TOLERANCE_RAD


def test_e_send_goal_ros2_reaches_a_remapped_action(shared: Shared) -> None:
    client = shared.run.start("send_goal", "send-goal", "stand", "{duration_s: 1.0}", "--ros2",
                              "--feedback", "--ros-args", "--remap",
                              f"stand:={REMAPPED_STAND}")
    assert client.wait(CLIENT_TIMEOUT_S) == 0, client.tail()
    out = client.output()
    assert f"Waiting for an action server to become available ({REMAPPED_STAND})" in out
    assert re.search(r"^Goal accepted with ID: [0-9a-f]{32}$", out, re.M)
    # The FR foot was left up by the trajectory: Stand puts it down, then rises.
    assert re.search(r"^Feedback \[ *\d+\.\d+ s\]: \{phase: placing_foot, progress: 0\.0\}$",
                     out, re.M), out
    assert re.search(r"^Feedback \[ *\d+\.\d+ s\]: \{phase: rising, progress: ", out, re.M)
    assert out.rstrip().endswith("Goal finished with status: SUCCEEDED")


def test_f_on_the_truth_the_high_five_held_and_the_cancel_ended_on_four_feet(
        shared: Shared) -> None:
    shared.node.send(signal.SIGINT)
    assert shared.node.wait(60.0) == 0, shared.node.tail()
    report = json.loads(shared.report.read_text())
    goals = report["goals"]
    assert [g["action"] for g in goals] == ["high_five", "high_five",
                                            "follow_joint_trajectory", "stand"], goals
    five, canceled = goals[0], goals[1]
    print(f"\nhigh five on the truth: raised foot {five['raised_foot_rms_mm']:.2f} mm RMS, "
          f"tilt {five['max_tilt_deg']:.2f} deg; canceled: final foot forces "
          f"{[round(f, 1) for f in canceled['final_foot_forces_n']]} N")
    assert five["raised_foot_rms_mm"] <= 5.0
    assert five["max_tilt_deg"] <= 3.0
    assert canceled["on_four_feet"], canceled
    # /odom (the estimate as published) against the truth at the same simulated time, in the
    # estimator's frame aligned on the first sample (it starts where the robot stands).
    truth_t = np.array(report["truth"]["t_s"])
    truth_q = np.array(report["truth"]["q"])
    odom = shared.odom
    assert len(odom) > 100
    t = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec for m in odom])
    rows = np.searchsorted(truth_t, t - 1e-6)
    keep = rows < len(truth_t)
    assert keep.sum() > 100
    p = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z]
                  for m in odom])[keep]
    near = np.abs(truth_t[rows[keep]] - t[keep]) <= 1e-3  # same tick (the report: every 4 ms)
    p, true_p = p[near], truth_q[rows[keep][near], :3]
    offset = true_p[0] - p[0]
    error_mm = 1e3 * np.linalg.norm(p + offset - true_p, axis=1)
    print(f"/odom against the truth over {len(p)} samples: {error_mm.max():.2f} mm at most, "
          f"{math.sqrt(np.mean(error_mm ** 2)):.2f} mm RMS; height "
          f"{1e3 * np.max(np.abs(p[:, 2] - true_p[:, 2])):.2f} mm at most")
    assert len(p) > 50
    assert error_mm.max() <= 10.0
    assert np.max(np.abs(p[:, 2] - true_p[:, 2])) <= 5e-3
