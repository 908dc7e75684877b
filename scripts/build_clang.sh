#!/usr/bin/env bash
# Builds the core, the command line and the Catch2 suite with the toolchain macOS uses — clang++ with libc++ and
# LLVM's OpenMP runtime (libomp) — into build-clang/, runs the suite, and compares the command line's mesh of a
# shared frame with the GCC build's (tests/portability/check_cli.py's comparison, without Wine).
# Installs what it needs; needs the GCC build (scripts/setup.sh) for the comparison.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
require_packages "${MENISCUS_CLANG_PACKAGES[@]}"
build=build-clang
CXX=clang++ CXXFLAGS="-stdlib=libc++" LDFLAGS="-stdlib=libc++" \
  /usr/bin/cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMENISCUS_BUILD_PYTHON=OFF \
  -DMENISCUS_FETCH_DEPENDENCIES=OFF > "$build-configure.log" 2>&1 || { cat "$build-configure.log"; exit 1; }
grep -q "libomp" "$build/CMakeCache.txt" || { echo "clang build does not use libomp" >&2; exit 1; }
/usr/bin/cmake --build "$build" -j"$(nproc)"
if ldd "$build/bin/meniscus_tests" | grep -q "libstdc++"; then
  echo "clang build links libstdc++, not libc++" >&2
  exit 1
fi

echo "== Catch2 suite (clang++, libc++, libomp)"
"$build/bin/meniscus_tests" "$@"
echo "== command line against the GCC build"
python3 tests/portability/check_cli.py --windows-cli "$build/bin/meniscus" --linux-cli build/bin/meniscus --label clang
