"""The ROS 2 tests (CI's third stage, ``make test-ros2``): skipped, with the reason, when the
ros2 extra (rclpy and the generated interfaces) is not installed; marked ``ros2`` so the main
stages deselect them. One ``go2-wbc ros2`` node process serves every test of a module."""

from __future__ import annotations

import importlib.util
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
MISSING = [name for name in ("rclpy", "go2_interfaces", "control_msgs")
           if importlib.util.find_spec(name) is None]
SKIP_REASON = (f"the ros2 extra is not installed ({', '.join(MISSING)} not importable): "
               "make install-ros2 (pip install -e '.[ros2]' and python -m "
               "go2_ros2.interface_build)")
#: The tests' own ROS 2 domain, apart from other runs on this machine; localhost only.
os.environ.setdefault("ROS_DOMAIN_ID", str(40 + os.getpid() % 50))
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        if Path(str(item.fspath)).resolve().is_relative_to(HERE):
            item.add_marker(pytest.mark.ros2)
            if MISSING:
                item.add_marker(pytest.mark.skip(reason=SKIP_REASON))


def client_argv(script: str, *args: str) -> list[str]:
    """A tutorial client of this folder, run by this Python."""
    return [sys.executable, str(HERE / script), *args]


class TopicRecorder:
    """Subscribes to topics in this process (its own ROS context and executor thread) and
    keeps every message with its wall-clock arrival time [s]."""

    def __init__(self, topics: dict[str, Any]) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.qos import qos_profile_sensor_data

        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = Node("go2_wbc_test_recorder", context=self.context)
        self.messages: dict[str, list[tuple[float, Any]]] = {name: [] for name in topics}
        self.recording = False
        for name, msg_type in topics.items():
            self.node.create_subscription(msg_type, name, self._keeper(name),
                                          qos_profile_sensor_data)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _keeper(self, name: str) -> Callable[[Any], None]:
        def keep(message: Any) -> None:
            if self.recording:
                self.messages[name].append((time.monotonic(), message))
        return keep

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException

        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass

    def close(self) -> None:
        import rclpy

        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture(scope="session")
def recorder() -> Iterator[TopicRecorder]:
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import JointState

    rec = TopicRecorder({"/joint_states": JointState, "/odom": Odometry})
    yield rec
    rec.close()
