#!/usr/bin/env bash
# Create .venv (when missing) and install the package with its test and scale (Ray) extras.
# Also installs Debian's Mesa OSMesa library, which offscreen video rendering needs, when
# it is missing and apt-get is usable (root or passwordless sudo); skipped otherwise.
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

if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e '.[test,scale]'
.venv/bin/python -c "import pinocchio, placo, mujoco, qpsolvers, daqp; print('setup: ok, pinocchio', pinocchio.__version__, 'placo imports, mujoco', mujoco.__version__)"
# Compile the controller's numba kernel once now (about 20 s), not on the first run.
echo "setup: compiling the controller kernel (once)"
.venv/bin/python -c "from wbc.controller.whole_body_controller import warm_up; warm_up()"
