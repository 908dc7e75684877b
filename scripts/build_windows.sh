#!/usr/bin/env bash
# Cross-compiles the core, the command line and the Catch2 suite for 64-bit Windows with mingw-w64 into
# build-windows/, then runs them under Wine:
#   - the whole Catch2 suite (meniscus_tests.exe);
#   - a CLI reconstruction of a shared frame, compared with the Linux build's mesh (same triangles, vertices within
#     float tolerance): tests/windows/compare_meshes.py;
#   - a particle file whose path has non-ASCII characters (Windows opens files by UTF-16 names).
# Installs what it needs (mingw-w64, Wine); needs the Linux build (scripts/setup.sh) for the comparison.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"
wine=/usr/lib/wine/wine64  # Debian's wine64 package does not put its loader on PATH
build=build-windows

mingw_cmake_arguments
/usr/bin/cmake -S . -B "$build" "${MINGW_CMAKE_ARGUMENTS[@]}" -DMENISCUS_BUILD_PYTHON=OFF > "$build-configure.log" 2>&1 || { cat "$build-configure.log"; exit 1; }
/usr/bin/cmake --build "$build" -j"$(nproc)"

export WINEPREFIX="$PWD/$build/wineprefix" WINEDEBUG=-all
[ -d "$WINEPREFIX" ] || "$wine" wineboot --init > /dev/null 2>&1 || true

echo "== Catch2 suite under Wine"
if [ $# -gt 0 ]; then
  "$wine" "$build/bin/meniscus_tests.exe" "$@"
else
  # In two processes at once: the test that writes and reads back every cut of every small sample spends half the
  # suite's two minutes waiting on Wine's file calls (2 s natively), while the cores are free for the rest. The rest
  # is everything that name does not match; --warn NoTests fails the first process if it matches nothing.
  cuts="every cut of every small sample*"
  "$wine" "$build/bin/meniscus_tests.exe" --warn NoTests "$cuts" > "$build/catch2-cuts.log" 2>&1 & cuts_process=$!
  rest_status=0 cuts_status=0
  "$wine" "$build/bin/meniscus_tests.exe" "~$cuts" || rest_status=$?
  wait "$cuts_process" || cuts_status=$?
  cat "$build/catch2-cuts.log"
  if [ "$rest_status" -ne 0 ] || [ "$cuts_status" -ne 0 ]; then exit 1; fi
fi

echo "== CLI under Wine against the Linux build"
python3 tests/portability/check_cli.py --wine "$wine" --windows-cli "$build/bin/meniscus.exe" --linux-cli build/bin/meniscus
