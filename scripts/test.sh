#!/usr/bin/env bash
# Runs every test; installs and builds first; exits non-zero on any failure (this is what .ci/run calls):
#   C++ (Catch2) and Python (pytest) suites; the packages users install (wheels for CPython 3.10/3.11/3.13 and the
#   Blender zips, built by scripts/package.sh) installed into clean environments; the headless Blender suite against
#   the installed add-on on Debian's Blender 3.4 (legacy zip) and on bpy 4.2, 4.5, 5.0 and 5.2 (extension zip); the
#   Windows cross-build under Wine, the Windows wheels in Windows CPython and the Windows extension zip in Windows
#   bpy 4.5 and 5.2 under Wine; the clang/libc++/libomp build under ASan/UBSan (the C++ suite and the command line);
#   a small run of the speed benchmark against pysplashsurf.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
started=$SECONDS
section() { echo "== $* ($((SECONDS - started)) s)"; }
# The tests share the cores (ctest -j2, the downloads below, other programs): OpenMP threads that spin at their
# barriers then take the cores from each other. Sleeping there instead changes no result, only the time: on 2 busy
# cores the C++ suite (ctest -j2) took 9 s instead of 93 s, test_mesh_pins.py + test_smoothing.py 20 s instead of
# 120 s.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"

# What only downloads runs beside the builds, which use the cores: the Debian packages of the clang build, the bpy
# wheels of the Blender suites (300-400 MB each) and the benchmark's reference venv. The packages the development
# build and scripts/package.sh (mingw-w64 and Wine, for the Windows packages) need come first (their apt-get must not
# wait for the other one's lock).
require_packages "${MENISCUS_BUILD_PACKAGES[@]}" "${MENISCUS_WINDOWS_PACKAGES[@]}" blender xvfb
mkdir -p build
(
  require_packages "${MENISCUS_CLANG_PACKAGES[@]}"
  for blender_version in 4.2 4.5 5.0 5.2; do bpy_venv "$blender_version" > /dev/null; done
  for blender_version in 4.5 5.2; do windows_bpy "$blender_version" > /dev/null; done  # for tests/windows/run.sh
  source bench/reference_venv.sh
) > build/downloads.log 2>&1 &
downloads=$!
wait_for_downloads() { wait "$downloads" || { echo "downloads failed:"; cat build/downloads.log; exit 1; }; }

bash scripts/setup.sh

section "C++ tests (ctest)"
/usr/bin/ctest --test-dir build --output-on-failure -j2

# Jobs beside the sections, each in its own process group, ended with this script if it stops early.
background_groups=()
trap 'for group in "${background_groups[@]}"; do kill -- -"$group" 2> /dev/null || true; done' EXIT
# beside LOG COMMAND...: starts COMMAND in the background, its output in LOG; sets $beside to its process id.
beside() {
  local log="$1"
  shift
  setsid -w "$@" > "$log" 2>&1 &
  beside=$!
  background_groups+=("$beside")
}

# The Mantaflow bakes need only Debian's Blender 3.4, nothing built here: they run beside the packages' builds, whose
# last files compile one at a time (alone they took 39-44 s, one core mostly idle).
beside build/bakes.log bash tests/mantaflow/bake.sh /usr/bin/blender
bakes=$beside

section "Packages: wheels and Blender zips (scripts/package.sh)"
bash scripts/package.sh > build/package.log 2>&1 || { tail -40 build/package.log; exit 1; }
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
extension="dist/meniscus-$version-linux_x64.zip"
legacy="dist/meniscus-$version-legacy-linux_x64.zip"

section "Mantaflow caches baked by Blender 3.4 (tests/mantaflow/bake.sh, run beside the packages)"
wait "$bakes" || { cat build/bakes.log; exit 1; }
cat build/bakes.log

section "Python tests (pytest: API, CLI, quality, packages)"
# One worker per core (pytest-xdist), each test file in one worker: the files' module fixtures (a baked sequence, a
# reconstructed frame) are then made once, as in one process.
/usr/bin/python3 -m pytest -q --durations=10 -n "$(nproc)" --dist loadfile tests/python

wait_for_downloads

section "Blender 3.4 (Debian) with the legacy add-on zip"
bash tests/blender/run.sh /usr/bin/blender "$legacy" legacy
for blender_version in 4.2 4.5 5.0 5.2; do
  section "Blender $blender_version (bpy from PyPI) with the extension zip"
  bash tests/blender/run.sh "$(bpy_venv "$blender_version")" "$extension" extension
done

# The clang/libc++/libomp build under ASan + UBSan and its suite run beside the Windows sections, in their own process
# group (ended with this script): Wine's programs leave about half of the cores idle, waiting on its server, and the
# build is compiles that take whatever core is free.
beside build/sanitizers.log bash scripts/test_sanitizers.sh
sanitizers=$beside

section "Windows: mingw-w64 cross-build, tests under Wine"
bash scripts/build_windows.sh > build/windows.log 2>&1 || { tail -60 build/windows.log; exit 1; }
grep -E "^All tests passed|^test cases|largest vertex difference|matches" build/windows.log
section "Windows packages under Wine: wheels in Windows CPython 3.10/3.11/3.13, the extension zip in Windows bpy 4.5/5.2"
bash tests/windows/run.sh > build/windows-packages.log 2>&1 || { tail -60 build/windows-packages.log; exit 1; }
grep -E "^== |^\(|^PASS|^NOT RUN|^all|passed under|refused|written|readers:" build/windows-packages.log

section "clang++ with libc++ and libomp (macOS's toolchain) under AddressSanitizer + UBSan (run beside the Windows sections)"
wait "$sanitizers" || { grep -v -E "Test +#[0-9]+: .* Passed" build/sanitizers.log | tail -80; exit 1; }
grep -E "tests passed|Total Test time|largest vertex difference|matches" build/sanitizers.log
section "Benchmark against pysplashsurf, small version (both tools run, meshes valid; timings not judged in CI)"
bash bench/compare.sh --quick
section "all tests passed"
