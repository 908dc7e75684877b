#!/usr/bin/env bash
# Builds the Catch2 tests with AddressSanitizer and UBSan (MENISCUS_SANITIZE=ON, no Python module, no CLI) into
# build-asan/ and runs all of them. Any sanitizer report fails the run: UBSan stops at its first finding
# (halt_on_error), ASan checks leaks as well.
#
#   scripts/test_sanitizers.sh [Catch2 test spec ...]     e.g. scripts/test_sanitizers.sh "[io],[formats],[bad-input]"
#
# With no argument every test runs, one process per test case, in parallel (ctest).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build-asan
# Only what the sanitizers must see: the core and the Catch2 suite (no CLI, no Python module). -O1 is what ASan is
# meant for (checks kept, a quicker compile than -O2); -g1 keeps the line tables the reports need without the full
# debug information, which made the RelWithDebInfo build of the suite take several times longer to compile.
/usr/bin/cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -g1" \
  -DMENISCUS_SANITIZE=ON -DMENISCUS_BUILD_PYTHON=OFF -DMENISCUS_BUILD_CLI=OFF > "$build-configure.log" 2>&1 \
  || { cat "$build-configure.log"; exit 1; }
/usr/bin/cmake --build "$build" -j"$(nproc)"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
echo "== C++ tests under ASan + UBSan ($build)"
if [ $# -gt 0 ]; then
  "$build/bin/meniscus_tests" "$@"
else
  # One process per test case (catch_discover_tests), as many at once as there are cores: the cases are
  # independent, and one process running them in turn leaves a core idle whenever a case runs on one thread. The
  # OpenMP threads of two processes on the same cores would spin at their barriers: they sleep there instead
  # (measured on 2 busy cores: 136 s against 184 s in one process, and less CPU time).
  OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}" /usr/bin/ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
fi
