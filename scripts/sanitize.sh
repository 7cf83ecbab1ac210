#!/usr/bin/env bash
# Builds the numeric core and its unit tests under AddressSanitizer and UndefinedBehaviorSanitizer
# (GCC) into build-sanitize/ and runs them; any report fails the run. Extra arguments go to ctest
# (e.g. -R Skinning). The integration tests are not run here: VTK, ITK and Python are not built with
# the sanitizers, and their own allocations would be reported.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${REPOSE_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
"$root/scripts/install-deps.sh"
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_C_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  >/dev/null
# Only the unit tests (tests/test_*.cpp) and the core libraries they link.
targets=$(cd "$root/tests" && ls test_*.cpp | sed 's/\.cpp$//')
cmake --build "$build" --target $targets
cd "$build"
# Leaks too; a unit test's process is short, so every allocation it forgets is reported.
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
# The leaks we accept (TetGen's error path) are listed, with why, in the suppressions file.
export LSAN_OPTIONS="suppressions=$root/scripts/sanitize-suppressions.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
ctest -L unit --output-on-failure -j 2 "$@"
