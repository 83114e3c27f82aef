"""The ROS 2 extra's interface build (go2_ros2.interface_build), without the extra: what it
builds from, its cache key, the rewrite of the wheels' build-image include paths, and the
one-line errors for missing tools. The build itself runs in CI's ROS 2 stage (tests/ros2)."""

from __future__ import annotations

import sys
import sysconfig
from pathlib import Path

import numpy as np
import pytest

from actions.action_type import INTERFACES_DIR
from go2_ros2 import interface_build
from go2_ros2.interface_build import (
    InterfaceBuildError,
    check_tools,
    fix_exported_include_dirs,
    source_files,
    sources_digest,
)


def test_the_go2_actions_are_the_library_s_own_definitions() -> None:
    files = source_files()
    for name in ("HighFive", "Stand", "Sit", "Walk"):
        assert files[f"go2_interfaces/action/{name}.action"] == (
            Path(INTERFACES_DIR) / f"{name}.action").read_bytes()
    assert {"go2_interfaces/CMakeLists.txt", "go2_interfaces/package.xml",
            "control_msgs/CMakeLists.txt", "control_msgs/package.xml",
            "control_msgs/action/FollowJointTrajectory.action",
            "control_msgs/msg/JointTolerance.msg",
            "control_msgs/msg/JointComponentTolerance.msg"} <= set(files)
    fjt = files["control_msgs/action/FollowJointTrajectory.action"].decode()
    assert "builtin_interfaces/Duration goal_time_tolerance" in fjt
    assert "int32 GOAL_TOLERANCE_VIOLATED = -5" in fjt


def test_the_cache_key_changes_with_any_source() -> None:
    files = source_files()
    digest = sources_digest(files)
    assert sources_digest(dict(files)) == digest
    changed = dict(files)
    changed["go2_interfaces/action/HighFive.action"] += b"\n# one more comment\n"
    assert sources_digest(changed) != digest


def test_the_wheels_build_image_include_paths_are_rewritten_once(tmp_path: Path) -> None:
    (tmp_path / "share" / "rosidl_default_generators").mkdir(parents=True)
    cmake = tmp_path / "share" / "action_msgs" / "cmake"
    cmake.mkdir(parents=True)
    tag = f"cp{sys.version_info[0]}{sys.version_info[1]}"
    version = f"{sys.version_info[0]}.{sys.version_info[1]}"
    image = f"/opt/python/{tag}-{tag}"
    export = cmake / "export_action_msgs__rosidl_generator_pyExport.cmake"
    export.write_text(
        f'  INTERFACE_INCLUDE_DIRECTORIES "{image}/include/python{version};'
        f'{image}/lib/python{version}/site-packages/numpy/_core/include"\n')
    untouched = cmake / "action_msgsConfig.cmake"
    untouched.write_text("set(x 1)\n")
    assert fix_exported_include_dirs(tmp_path) == 1
    text = export.read_text()
    assert "/opt/python" not in text
    assert sysconfig.get_paths()["include"] in text and np.get_include() in text
    assert fix_exported_include_dirs(tmp_path) == 0  # already done
    assert untouched.read_text() == "set(x 1)\n"


def test_a_prefix_without_the_wheels_says_how_to_install_them(tmp_path: Path) -> None:
    with pytest.raises(InterfaceBuildError, match=r"pip install 'go2-wbc\[ros2\]'"):
        fix_exported_include_dirs(tmp_path)


def test_a_missing_compiler_is_named_with_how_to_install_one(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setattr(interface_build.shutil, "which",
                        lambda name, path=None: None if name in ("cc", "gcc")
                        else f"/usr/bin/{name}")
    with pytest.raises(InterfaceBuildError, match=r"no C compiler found .*apt-get install gcc"):
        check_tools()
