#!/usr/bin/env bash
# Build go2_peer, a Cyclone DDS 0.10.x C peer (the stack of unitree_sdk2 and unitree_mujoco),
# from unitree_go.idl and go2_peer.c with the system's idlc and libddsc.
#
#   bash scripts/go2_peer/build.sh [OUT_DIR]
#
# OUT_DIR defaults to ${XDG_CACHE_HOME:-~/.cache}/go2-wbc/go2_peer; the generated C and the binary
# go there, never into the source tree. Prints the binary's path as its last line.
# Needs Debian's cyclonedds-tools (idlc) and cyclonedds-dev (headers, libddsc) 0.10.x, and gcc;
# exits 3 naming the missing package otherwise.
set -euo pipefail
SRC="$(cd "$(dirname "$0")" && pwd)"
OUT="${1:-${XDG_CACHE_HOME:-$HOME/.cache}/go2-wbc/go2_peer}"

missing() { echo "build.sh: $1 not found: apt-get install $2" >&2; exit 3; }
command -v idlc >/dev/null 2>&1 || missing "idlc" "cyclonedds-tools"
[ -f /usr/include/dds/dds.h ] || [ -f /usr/local/include/dds/dds.h ] \
  || missing "dds/dds.h" "cyclonedds-dev"
CC="${CC:-gcc}"
command -v "$CC" >/dev/null 2>&1 || missing "$CC" "gcc"
IDLC_VERSION="$(idlc -v 2>&1 | grep -o '[0-9][0-9.]*' | head -n 1)"
case "$IDLC_VERSION" in
  0.10.*) ;;
  *) echo "build.sh: idlc is $IDLC_VERSION, the peer must be built with Cyclone DDS 0.10.x" >&2
     exit 3 ;;
esac

mkdir -p "$OUT"
# Build in a scratch directory next to OUT and move the result in, so that a concurrent build
# never leaves a half-written binary behind.
WORK="$(mktemp -d "$OUT/.build.XXXXXX")"
trap 'rm -rf "$WORK"' EXIT
idlc -l c -o "$WORK" "$SRC/unitree_go.idl"
DDS_FLAGS="$(pkg-config --cflags --libs CycloneDDS 2>/dev/null || echo -lddsc)"
# shellcheck disable=SC2086  # DDS_FLAGS is a list of flags
"$CC" -std=c11 -O2 -Wall -Wextra -Werror -I "$WORK" -o "$WORK/go2_peer" \
  "$SRC/go2_peer.c" "$WORK/unitree_go.c" $DDS_FLAGS
mv -f "$WORK/unitree_go.c" "$WORK/unitree_go.h" "$OUT/"
mv -f "$WORK/go2_peer" "$OUT/go2_peer"
echo "$OUT/go2_peer"
