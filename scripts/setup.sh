#!/usr/bin/env bash
# Create .venv (when missing) and install the package with its test, scale (Ray) and solvers
# (quadprog, GPL: the benchmark's comparison) extras.
# Also installs, when they are missing and apt-get is usable (root or passwordless sudo), Debian's
# Mesa OSMesa library (offscreen video rendering), Cyclone DDS 0.10.x in C (the DDS interop
# test's peer) and Xvfb (the viewer window's test); skipped otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}

# apt_install WHAT PACKAGE...: install Debian packages when apt-get is usable (root or
# passwordless sudo); otherwise, or when it fails, say what WHAT will lack.
apt_install() {
  local what=$1
  shift
  command -v apt-get >/dev/null 2>&1 || return 0
  local sudo=""
  [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo="sudo -n"
  [ "$(id -u)" -eq 0 ] || [ -n "$sudo" ] || return 0
  echo "setup: installing $* ($what)"
  ($sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq "$@" >/dev/null) \
    || echo "setup: could not install $*; $what will be unavailable"
}

if ! ldconfig -p 2>/dev/null | grep -q libOSMesa; then
  apt_install "offscreen rendering for --video" libosmesa6
fi
# Cyclone DDS 0.10.x in C (idlc, headers, libddsc), the stack of unitree_sdk2 and unitree_mujoco:
# tests/test_dds_interop.py builds a 0.10.x peer with it (and skips, naming the package, without).
if ! command -v idlc >/dev/null 2>&1 || [ ! -f /usr/include/dds/dds.h ]; then
  apt_install "the DDS interop test's 0.10.x peer" cyclonedds-dev cyclonedds-tools
fi
# A virtual screen with software OpenGL: tests/test_viewer_window.py opens the --viewer window
# on it (and skips, naming the package, without).
if ! command -v Xvfb >/dev/null 2>&1; then
  apt_install "the viewer window's test" xvfb libgl1-mesa-dri
fi

if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install -q --upgrade pip
# editable_mode=compat: the checkout on sys.path through a plain .pth line, which mypy and
# pyright read from outside the checkout (setuptools' default editable install is an import
# hook they cannot see: "Cannot find implementation or library stub for module 'wbc'").
.venv/bin/python -m pip install -q -e '.[test,scale,solvers]' --config-settings editable_mode=compat
# pyright (the npm registry's, pinned) for tests/test_typed_messages.py, which runs it on a
# user's scripts from outside the checkout; skipped (the test says so) where npm is missing.
if command -v npm >/dev/null 2>&1 && [ ! -x .venv/node_modules/.bin/pyright ]; then
  npm install --silent --no-audit --no-fund --prefix .venv pyright@1.1.414 \
    || echo "setup: could not install pyright; its test will be skipped"
fi
.venv/bin/python -c "import pinocchio, placo, mujoco, qpsolvers, daqp; print('setup: ok, pinocchio', pinocchio.__version__, 'placo imports, mujoco', mujoco.__version__)"
# Compile the numba kernels once now, not on the first run (about 80 s on 2 cores): a high
# five with each estimator, in two processes at once, compiles the controller's, the tasks',
# the simulated sensors', the shaper's and both estimators' kernels into numba's cache. A
# failure here only means the first run compiles them itself.
echo "setup: compiling the kernels (once, about a minute)"
warm() { .venv/bin/go2-wbc high-five --hold 0 --estimator "$1" > /dev/null 2>&1; }
warm inekf & inekf=$!
warm kf & kf=$!
wait "$inekf" && wait "$kf" || echo "setup: the kernels' warm-up failed; the first run compiles them"
# A short walk: the gait's kernels and the two-foot layouts' tick programs (about 30 s).
.venv/bin/go2-wbc walk --forward 0.3 --duration 0.6 > /dev/null 2>&1 \
  || echo "setup: the walk's warm-up failed; the first walk compiles its kernels"
