#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test (unit, integration, Python, image baselines).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${REPOSE_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh"
cd "$build"
# Image tests render offscreen and need an X server.
if [ -z "${DISPLAY:-}" ]; then
  exec xvfb-run -a -s "-screen 0 1600x1200x24" ctest --output-on-failure -j 2 "$@"
fi
exec ctest --output-on-failure -j 2 "$@"
