#!/usr/bin/env bash
# Installs what is missing, builds, and runs `repose demo` (outputs in ./repose-demo).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${REPOSE_BUILD_DIR:-$root/build}"
"$root/scripts/build.sh"
"$build/bin/repose" demo "$@"
