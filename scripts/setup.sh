#!/usr/bin/env bash
# Create .venv (when missing) and install the package with its test and scale (Ray) extras.
# Also installs Debian's Mesa OSMesa library, which offscreen video rendering needs, and Cyclone
# DDS 0.10.x in C, which the DDS interop test builds a peer with, when they are missing and
# apt-get is usable (root or passwordless sudo); skipped otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}

if ! ldconfig -p 2>/dev/null | grep -q libOSMesa; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && SUDO="sudo -n"
    if [ "$(id -u)" -eq 0 ] || [ -n "$SUDO" ]; then
      echo "setup: installing libosmesa6 (offscreen rendering for --video)"
      ($SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq libosmesa6 >/dev/null) \
        || echo "setup: could not install libosmesa6; --video will be unavailable"
    fi
  fi
fi

# Cyclone DDS 0.10.x in C (idlc, headers, libddsc), the stack of unitree_sdk2 and unitree_mujoco:
# tests/test_dds_interop.py builds a 0.10.x peer with it (and skips, naming the package, without).
if ! command -v idlc >/dev/null 2>&1 || [ ! -f /usr/include/dds/dds.h ]; then
  if command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && SUDO="sudo -n"
    if [ "$(id -u)" -eq 0 ] || [ -n "$SUDO" ]; then
      echo "setup: installing cyclonedds-dev cyclonedds-tools (Cyclone DDS 0.10.x C, DDS interop test)"
      ($SUDO apt-get update -qq \
        && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq cyclonedds-dev cyclonedds-tools >/dev/null) \
        || echo "setup: could not install cyclonedds-dev cyclonedds-tools; the DDS interop test will skip"
    fi
  fi
fi

if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e '.[test,scale]'
.venv/bin/python -c "import pinocchio, placo, mujoco, qpsolvers, daqp; print('setup: ok, pinocchio', pinocchio.__version__, 'placo imports, mujoco', mujoco.__version__)"
# Compile the controller's numba kernel once now (about 20 s), not on the first run.
echo "setup: compiling the controller kernel (once)"
.venv/bin/python -c "from wbc.controller.whole_body_controller import warm_up; warm_up()"
