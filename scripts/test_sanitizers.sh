#!/usr/bin/env bash
# Builds the Catch2 tests with AddressSanitizer and UBSan (MENISCUS_SANITIZE=ON, no Python module, no CLI) into
# build-asan/ and runs all of them. Any sanitizer report fails the run: UBSan stops at its first finding
# (halt_on_error), ASan checks leaks as well.
#
#   scripts/test_sanitizers.sh [Catch2 test spec ...]     e.g. scripts/test_sanitizers.sh "[io],[formats],[bad-input]"
#
# With no argument every test runs (the whole suite takes several minutes under the sanitizers on 2 cores).
set -euo pipefail
cd "$(dirname "$0")/.."

build=build-asan
# RelWithDebInfo: optimised enough to finish in minutes, with line numbers in the reports.
/usr/bin/cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMENISCUS_SANITIZE=ON -DMENISCUS_BUILD_PYTHON=OFF \
  -DMENISCUS_BUILD_CLI=OFF > "$build-configure.log" 2>&1 || { cat "$build-configure.log"; exit 1; }
/usr/bin/cmake --build "$build" -j"$(nproc)"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
echo "== C++ tests under ASan + UBSan ($build)"
"$build/bin/meniscus_tests" "$@"
