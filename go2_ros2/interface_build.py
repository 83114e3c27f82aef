"""Builds the ROS 2 interface packages the node serves (``go2_interfaces``, ``control_msgs``)
with the rosidl tool chain of the ``ros2`` extra's wheels, into the running Python's prefix.

``python -m go2_ros2.interface_build`` (``make install-ros2`` runs it) copies the library's own
``HighFive``, ``Stand`` and ``Sit`` definitions (``actions/interfaces/*.action``) into the
``go2_interfaces`` package, configures both packages with CMake and Ninja (the ``cmake`` and
``ninja`` wheels: no root) against the prefix, builds and installs them there, so that
``from go2_interfaces.action import HighFive`` and
``from control_msgs.action import FollowJointTrajectory`` import as in any ROS 2 install.
A C and C++ compiler and Python's headers are assumed; their absence is said in one line.

Cached: the build is skipped when the hash of every definition and build file (and the
Python version) matches the stamp of the last build and the packages import.

Two traps of the wheels are handled here (``ROS2-FACTS.md``):

- their exported CMake targets carry the include directories of the image they were built
  in (``/opt/python/cp3XX-cp3XX/...``: Python's and numpy's headers); CMake refuses a target
  whose include directory does not exist, so those paths are rewritten, in the prefix's own
  target files, to this Python's and this numpy's (the prefix is the user's virtual
  environment: no root);
- the generated libraries must be found by the loader: they get an RPATH (their own
  directory and the prefix's ``lib/``), so nothing global (``LD_LIBRARY_PATH``) is needed.
"""

from __future__ import annotations

import argparse
import hashlib
import importlib
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import time
from dataclasses import dataclass
from pathlib import Path

from actions.action_type import INTERFACES_DIR

#: The interface packages' sources (package.xml, CMakeLists.txt and the control_msgs
#: definitions), shipped with this package.
PACKAGES_DIR = Path(__file__).resolve().parent / "packages"
#: The GO2's actions copied from the library's definitions into ``go2_interfaces``.
GO2_ACTIONS = ("HighFive", "Stand", "Sit", "Walk")
#: Built in this order; each is importable as ``<name>.action`` afterwards.
PACKAGE_NAMES = ("go2_interfaces", "control_msgs")
#: The modules the build must make importable.
CHECK_IMPORTS = ("go2_interfaces.action", "control_msgs.action")
#: Bump to rebuild when this module's way of building changes.
BUILD_FORMAT = 1


class InterfaceBuildError(RuntimeError):
    """The interface packages could not be built: what is missing and how to get it."""


@dataclass(frozen=True)
class BuildReport:
    """What :func:`build_interfaces` did.

    Attributes:
        built: Whether it built (``False``: the cache was up to date).
        seconds: Wall time of the call [s].
        digest: The sources' hash the stamp records.
        prefix: Where the packages are installed.
    """

    built: bool
    seconds: float
    digest: str
    prefix: Path


def source_files() -> dict[str, bytes]:
    """Every file the build reads, by its path in the generated source tree."""
    files = {}
    for path in sorted(PACKAGES_DIR.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            files[path.relative_to(PACKAGES_DIR).as_posix()] = path.read_bytes()
    for name in GO2_ACTIONS:
        files[f"go2_interfaces/action/{name}.action"] = (
            Path(INTERFACES_DIR) / f"{name}.action").read_bytes()
    return files


def sources_digest(files: dict[str, bytes]) -> str:
    """The SHA-256 of the sources, the build format and the Python version."""
    digest = hashlib.sha256(f"{BUILD_FORMAT} {sys.version_info[:2]}".encode())
    for name, data in sorted(files.items()):
        digest.update(name.encode() + b"\0" + hashlib.sha256(data).digest())
    return digest.hexdigest()


def stamp_path(prefix: Path) -> Path:
    """The stamp of the last build in ``prefix``."""
    return prefix / "share" / "go2_wbc_ros2" / "interfaces.json"


def check_tools() -> dict[str, str]:
    """The tools the build needs, by name.

    Raises:
        InterfaceBuildError: One is missing, naming it and how to install it.
    """
    bin_dir = Path(sys.executable).parent
    tools = {}
    for name, hint in (("cmake", "pip install cmake"), ("ninja", "pip install ninja")):
        found = shutil.which(name, path=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
        if found is None:
            raise InterfaceBuildError(f"{name} not found; install the ros2 extra "
                                      f"(pip install 'go2-wbc[ros2]') or run: {hint}")
        tools[name] = found
    compiler = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc")
    if compiler is None:
        raise InterfaceBuildError(
            "no C compiler found (cc, gcc or $CC); the interface packages are compiled C. "
            "Install one: Debian/Ubuntu 'apt-get install gcc', Fedora 'dnf install gcc', "
            "macOS 'xcode-select --install'")
    tools["cc"] = compiler
    cxx = os.environ.get("CXX") or shutil.which("c++") or shutil.which("g++")
    if cxx is None:  # rosidl's C++ type supports are compiled too
        raise InterfaceBuildError(
            "no C++ compiler found (c++, g++ or $CXX); the interface packages' type supports "
            "are compiled C++. Install one: Debian/Ubuntu 'apt-get install g++', Fedora "
            "'dnf install gcc-c++', macOS 'xcode-select --install'")
    tools["cxx"] = cxx
    headers = Path(sysconfig.get_paths()["include"])
    if not (headers / "Python.h").is_file():
        raise InterfaceBuildError(
            f"Python's C headers not found (no Python.h in {headers}); the interface packages "
            f"build a Python extension. Install them: Debian/Ubuntu 'apt-get install "
            f"python3-dev' (or python{sys.version_info[0]}.{sys.version_info[1]}-dev)")
    return tools


def fix_exported_include_dirs(prefix: Path) -> int:
    """Rewrite, in the prefix's CMake target files, the wheels' build-image Python and numpy
    include directories (``/opt/python/cp3XX-cp3XX/...``) to this Python's and numpy's.

    Returns:
        The number of files rewritten (0 when already done).

    Raises:
        InterfaceBuildError: The rosidl wheels are not installed in ``prefix``.
    """
    import numpy

    share = prefix / "share"
    if not (share / "rosidl_default_generators").is_dir():
        raise InterfaceBuildError(
            f"the rosidl wheels are not installed in {prefix}; install the ros2 extra first: "
            f"pip install 'go2-wbc[ros2]'")
    tag = f"cp{sys.version_info[0]}{sys.version_info[1]}"
    image = f"/opt/python/{tag}-{tag}"
    site = f"lib/python{sys.version_info[0]}.{sys.version_info[1]}/site-packages"
    swaps = {f"{image}/{site}/numpy/_core/include": numpy.get_include(),
             f"{image}/{site}/numpy/core/include": numpy.get_include(),
             f"{image}/include/python{sys.version_info[0]}.{sys.version_info[1]}":
                 sysconfig.get_paths()["include"]}
    rewritten = 0
    for path in sorted(share.glob("*/cmake/*Export.cmake")):
        text = path.read_text()
        if "/opt/python/" not in text:
            continue
        new = text
        for old, actual in swaps.items():
            new = new.replace(old, actual)
        if new != text:
            path.write_text(new)
            rewritten += 1
    return rewritten


def _run(command: list[str], *, log: Path, env: dict[str, str]) -> None:
    with log.open("a") as out:
        out.write("$ " + " ".join(command) + "\n")
        out.flush()
        done = subprocess.run(command, stdout=out, stderr=subprocess.STDOUT, env=env,
                              check=False)
    if done.returncode != 0:
        tail = "\n".join(log.read_text().splitlines()[-25:])
        raise InterfaceBuildError(f"{command[0]} failed (exit {done.returncode}); the last "
                                  f"lines of {log}:\n{tail}")


def _importable(prefix: Path) -> bool:
    """Whether the built packages import in a fresh interpreter of this Python."""
    code = "; ".join(f"import {name}" for name in CHECK_IMPORTS)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, check=False)
    return done.returncode == 0


def build_interfaces(*, prefix: Path | None = None, work_dir: Path | None = None,
                     force: bool = False, jobs: int = 2) -> BuildReport:
    """Build and install ``go2_interfaces`` and ``control_msgs`` into ``prefix``, unless the
    stamp says the same sources were built there and they import.

    Args:
        prefix: The install prefix, where the ros2 extra's wheels are (default: this
            Python's, ``sys.prefix``: the virtual environment).
        work_dir: Where the sources are laid out and built (default: ``<prefix>/share/
            go2_wbc_ros2/build``).
        force: Build even when the cache is up to date.
        jobs: Parallel compile jobs.

    Raises:
        InterfaceBuildError: A missing tool or wheel, or a failed step (with its log's tail).
    """
    start = time.monotonic()
    prefix = Path(sys.prefix if prefix is None else prefix).resolve()
    files = source_files()
    digest = sources_digest(files)
    stamp = stamp_path(prefix)
    if (not force and stamp.is_file()
            and json.loads(stamp.read_text()).get("digest") == digest and _importable(prefix)):
        return BuildReport(False, time.monotonic() - start, digest, prefix)
    tools = check_tools()
    fix_exported_include_dirs(prefix)
    work = Path(work_dir) if work_dir is not None else stamp.parent / "build"
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    for name, data in files.items():
        (work / "src" / name).parent.mkdir(parents=True, exist_ok=True)
        (work / "src" / name).write_bytes(data)
    env = dict(os.environ)
    env["PATH"] = f"{Path(tools['cmake']).parent}{os.pathsep}{env.get('PATH', '')}"
    env["AMENT_PREFIX_PATH"] = str(prefix)
    env.setdefault("CC", tools["cc"])
    env.setdefault("CXX", tools["cxx"])
    log = work / "build.log"
    lib = prefix / "lib"
    for package in PACKAGE_NAMES:
        build = work / "build" / package
        _run([tools["cmake"], "-S", str(work / "src" / package), "-B", str(build),
              "-G", "Ninja", f"-DCMAKE_MAKE_PROGRAM={tools['ninja']}",
              f"-DCMAKE_PREFIX_PATH={prefix}", f"-DCMAKE_INSTALL_PREFIX={prefix}",
              f"-DPython3_EXECUTABLE={sys.executable}", "-DBUILD_TESTING=OFF",
              "-DCMAKE_BUILD_TYPE=Release",
              # The loader finds the generated libraries beside each other and the wheels'.
              f"-DCMAKE_INSTALL_RPATH=$ORIGIN;{lib}", "-DCMAKE_BUILD_WITH_INSTALL_RPATH=ON"],
             log=log, env=env)
        _run([tools["cmake"], "--build", str(build), "--parallel", str(jobs)], log=log, env=env)
        _run([tools["cmake"], "--install", str(build)], log=log, env=env)
    importlib.invalidate_caches()
    if not _importable(prefix):
        raise InterfaceBuildError(
            f"built and installed into {prefix}, but {', '.join(CHECK_IMPORTS)} do not import "
            f"with {sys.executable}; see {log}")
    stamp.write_text(json.dumps({"digest": digest, "packages": list(PACKAGE_NAMES)}) + "\n")
    return BuildReport(True, time.monotonic() - start, digest, prefix)


def main(argv: list[str] | None = None) -> int:
    """``python -m go2_ros2.interface_build [--force]``: build (or find up to date) the
    interface packages; one line saying which, and how long it took."""
    parser = argparse.ArgumentParser(prog="python -m go2_ros2.interface_build",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="build even if up to date")
    parser.add_argument("--jobs", type=int, default=2, help="parallel compile jobs")
    args = parser.parse_args(argv)
    try:
        report = build_interfaces(force=args.force, jobs=args.jobs)
    except InterfaceBuildError as err:
        print(f"go2-wbc ros2 interfaces: {err}", file=sys.stderr)
        return 1
    what = "built and installed" if report.built else "up to date (cached)"
    print(f"go2-wbc ros2 interfaces: {', '.join(PACKAGE_NAMES)} {what} in {report.prefix} "
          f"({report.seconds:.1f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
