"""The GO2's wire has one home, ``wbc/robot_io/dds/``: no other module of the library or the
benchmarks imports cyclonedds (at any depth of its code), and the two ends of the topic pair
made there talk to each other with unitree_sdk2's QoS (:mod:`wbc.robot_io.dds.controller_end`,
:mod:`wbc.robot_io.dds.robot_end`, :mod:`wbc.robot_io.dds.sdk_qos`,
:mod:`wbc.robot_io.dds.topic_endpoints`)."""

from __future__ import annotations

import ast
import os
import time
from pathlib import Path

import pytest

from wbc.core.errors import ConfigurationError
from wbc.robot_io.dds.c_layout import LOW_STATE_DTYPE, sdk_default_low_cmd, zero_record
from wbc.robot_io.dds.controller_end import ControllerEnd
from wbc.robot_io.dds.domain_config import join_domain
from wbc.robot_io.dds.robot_end import RobotEnd
from wbc.robot_io.dds.sdk_qos import sdk_reader_qos, sdk_writer_qos
from wbc.robot_io.dds.sim_truth import SIM_TRUTH_TOPIC, SimTruthMessage
from wbc.robot_io.dds.topic_endpoints import TopicReader
from wbc.robot_io.dds.wire_message import LowCmdMessage, LowStateMessage

ROOT = Path(__file__).resolve().parents[1]
#: The wire's one home, and where cyclonedds may not be imported.
HOME = Path("wbc/robot_io/dds")
CHECKED = ("wbc", "tasks", "sim", "actions", "benchmarks")
DOMAIN = 151 + os.getpid() % 8  # concurrent runs stay apart (others: 150, 160 to 231)
WAIT_S = 5.0


def cyclonedds_imports(source: str) -> list[int]:
    """The lines of ``source`` that import cyclonedds: ``import``/``from`` statements at any
    depth (inside functions, ``if TYPE_CHECKING``, ``try``), and ``importlib.import_module`` /
    ``__import__`` calls given the name."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [node.module or ""] if node.level == 0 else []
        elif (isinstance(node, ast.Call) and node.args
              and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)
              and getattr(node.func, "attr", getattr(node.func, "id", None))
              in ("import_module", "__import__")):
            names = [node.args[0].value]
        else:
            continue
        if any(name == "cyclonedds" or name.startswith("cyclonedds.") for name in names):
            lines.append(node.lineno)
    return lines


def test_the_finder_sees_imports_at_any_depth() -> None:
    source = ("import os\n"
              "def f():\n"
              "    from cyclonedds.core import Qos\n"
              "if True:\n"
              "    import cyclonedds.idl.types as t\n"
              "importlib.import_module('cyclonedds.pub')\n"
              "from cyclonedds_extra import x\n"      # another package: not cyclonedds
              "from .cyclonedds import y\n")          # a relative module: not cyclonedds
    assert cyclonedds_imports(source) == [3, 5, 6]


def test_cyclonedds_is_imported_only_in_the_wires_home() -> None:
    outside, inside = [], []
    for package in CHECKED:
        for path in sorted((ROOT / package).rglob("*.py")):
            lines = cyclonedds_imports(path.read_text(encoding="utf-8"))
            relative = path.relative_to(ROOT)
            if lines:
                (inside if relative.is_relative_to(HOME) else outside).append(
                    f"{relative}:{lines[0]}")
    assert outside == [], f"cyclonedds imported outside {HOME}/: {outside}"
    assert len(inside) >= 5  # the finder does find the home's own imports


def test_the_sdk_qos_and_its_depth_check() -> None:
    assert sdk_writer_qos() == sdk_writer_qos() and sdk_reader_qos(4) == sdk_reader_qos(4)
    assert sdk_reader_qos() != sdk_reader_qos(16)
    with pytest.raises(ConfigurationError, match=r"depth: expected a history depth, an int "
                                                 r">= 1 \[samples\], received 0"):
        sdk_reader_qos(0)


@pytest.fixture(scope="module")
def ends():
    robot = RobotEnd(domain_id=DOMAIN, interface="lo", command_depth=4)
    controller = ControllerEnd(domain_id=DOMAIN, interface="lo")
    yield robot, controller
    controller.close()
    robot.close()


def test_the_two_ends_of_the_topic_pair_talk(ends) -> None:
    robot, controller = ends
    assert controller.wait_for_command_reader(WAIT_S)
    state = zero_record(LOW_STATE_DTYPE)
    state["tick"] = 7
    deadline = time.monotonic() + WAIT_S
    while not controller.state_writers_matched() and time.monotonic() < deadline:
        time.sleep(1e-3)
    robot.write_state(LowStateMessage(state))
    assert controller.wait_for_state(WAIT_S)
    assert controller.state_pending
    assert [int(r["tick"]) for r in controller.take_states()] == [7]
    assert not controller.state_pending
    command = sdk_default_low_cmd()
    for reserve in (1, 2, 3):  # the robot's reader keeps them all (depth 4)
        command["reserve"] = reserve
        assert controller.write_command(LowCmdMessage(command))  # a reader was matched
    taken = []
    deadline = time.monotonic() + WAIT_S
    while len(taken) < 3 and time.monotonic() < deadline:
        robot.wait_for_command(0.05)
        taken += [int(s.record["reserve"]) for s in robot.take_commands()
                  if s.sample_info.valid_data]
    assert taken == [1, 2, 3]


def test_the_truth_topic_reaches_a_reader_of_it(ends) -> None:
    robot, _ = ends
    with join_domain("lo", domain_id=DOMAIN) as dds:
        reader = TopicReader(dds, SIM_TRUTH_TOPIC, SimTruthMessage, qos=sdk_reader_qos())
        truth = SimTruthMessage()
        truth.record["tick"], truth.record["q"][2] = 11, 0.3
        newest = None
        deadline = time.monotonic() + WAIT_S
        while newest is None and time.monotonic() < deadline:
            robot.write_truth(truth)  # BestEffort: written until the reader has matched
            time.sleep(0.01)
            newest = reader.take_newest()
        reader.close()
        reader.close()  # idempotent
    assert newest is not None and int(newest.record["tick"]) == 11
    assert float(newest.record["q"][2]) == 0.3


def test_a_dry_run_end_writes_nothing_and_closes_once() -> None:
    end = ControllerEnd(domain_id=DOMAIN, interface="lo", write_commands=False)
    assert end.write_command(LowCmdMessage(sdk_default_low_cmd()))  # nowhere to go: not unmatched
    assert end.wait_for_command_reader(0.0)
    assert not end.wait_for_state(0.0)
    end.close()
    end.close()
    assert end.is_closed


def test_a_bad_depth_joins_no_domain() -> None:
    with pytest.raises(ConfigurationError, match="depth"):
        RobotEnd(domain_id=DOMAIN, interface="lo", command_depth=0)
    with pytest.raises(ConfigurationError, match="interface"):
        RobotEnd(domain_id=DOMAIN, interface="nosuch0", command_depth=4)


def test_the_truth_types_old_import_path_names_the_same_objects() -> None:
    import sim.sim_truth as old
    import wbc.robot_io.dds.sim_truth as home

    for name in ("SIM_TRUTH_DTYPE", "SIM_TRUTH_TOPIC", "SimTruth", "SimTruthMessage"):
        assert getattr(old, name) is getattr(home, name), name
