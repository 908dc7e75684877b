#!/usr/bin/env bash
# Builds the core, the command line and the Catch2 suite with the toolchain macOS uses — clang++ with libc++ and LLVM's
# OpenMP runtime (libomp) — under AddressSanitizer and UBSan, into build-clang-asan/, and runs:
#   - every Catch2 test case (any sanitizer report fails the run: UBSan stops at its first finding, ASan checks leaks
#     as well);
#   - the command line on a shared frame, its mesh compared with the GCC build's (tests/portability/check_cli.py's
#     comparison, without Wine).
# One build for both (the portability build and the sanitizer build were two, compiling the core twice).
# Installs what it needs; needs the GCC build (scripts/setup.sh) for the comparison.
#
#   scripts/test_sanitizers.sh [Catch2 test spec ...]     e.g. scripts/test_sanitizers.sh "[io],[formats],[bad-input]"
#
# With no argument every test runs, one process per test case, in parallel (ctest), then the command line's check.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
require_packages "${MENISCUS_CLANG_PACKAGES[@]}"

build=build-clang-asan
# No Python module. -O1 is what ASan is meant for (checks kept, a quicker compile than -O2); -g1 keeps the line tables
# the reports need without the full debug information, which made the RelWithDebInfo build of the suite take several
# times longer to compile.
CXX=clang++ CXXFLAGS="-stdlib=libc++" LDFLAGS="-stdlib=libc++" \
  /usr/bin/cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_FLAGS_SANITIZE="-O1 -g1" \
  -DMENISCUS_SANITIZE=ON -DMENISCUS_BUILD_PYTHON=OFF -DMENISCUS_FETCH_DEPENDENCIES=OFF > "$build-configure.log" 2>&1 \
  || { cat "$build-configure.log"; exit 1; }
grep -q "libomp" "$build/CMakeCache.txt" || { echo "clang build does not use libomp" >&2; exit 1; }
/usr/bin/cmake --build "$build" -j"$(nproc)"
if ldd "$build/bin/meniscus_tests" | grep -q "libstdc++"; then
  echo "clang build links libstdc++, not libc++" >&2
  exit 1
fi

# libomp keeps its thread pool's allocations to the end of the process, which LeakSanitizer reports as leaks
# (tests/native/lsan_suppressions.txt: libomp's own frames only).
export LSAN_OPTIONS="suppressions=$PWD/tests/native/lsan_suppressions.txt${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
echo "== C++ tests under ASan + UBSan (clang++, libc++, libomp: $build)"
if [ $# -gt 0 ]; then
  "$build/bin/meniscus_tests" "$@"
  exit
fi
# One process per test case (catch_discover_tests), as many at once as there are cores: the cases are independent,
# and one process running them in turn leaves a core idle whenever a case runs on one thread. The OpenMP threads of
# two processes on the same cores would spin at their barriers: they sleep there instead (measured on 2 busy cores:
# 136 s against 184 s in one process, and less CPU time).
OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}" /usr/bin/ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
echo "== command line (clang++, libc++, libomp, ASan + UBSan) against the GCC build"
python3 tests/portability/check_cli.py --windows-cli "$build/bin/meniscus" --linux-cli build/bin/meniscus --label clang
