#!/usr/bin/env bash
# The Windows packages of dist/ (scripts/package_windows.sh) tested under Wine, as scripts/test.sh's Windows section
# runs them: each win_amd64 wheel installed with pip into its Windows CPython from PyPI (scripts/lib.sh:
# windows_python), then tests/windows/test_wheels.py (3.11 and 3.13: the Python API, the console script, readers,
# exit codes, non-ASCII names, a long path, against the Linux build; 3.10: install, import and one frame); then the
# headless Blender suite (tests/blender/run.sh) with the extension zip installed into the Windows `bpy` 4.5 (Windows
# CPython 3.11) and 5.2 (3.13) from PyPI (tests/windows/python-wine). Python 3.13 runs with the harness's Wine shims
# (tests/windows/wine_shims.py: numpy 2.x and bpy 5.2 under Wine 8).
# Needs the Linux build (build/bin/meniscus), the mingw-w64 build (build-windows/, scripts/build_windows.sh: the
# command line the farm and bake tests run) and dist/.
#   bash tests/windows/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
# WINEDLLOVERRIDES: the ucrtbase.dll shim that wine_shims (below) puts beside each Windows python.exe.
export WINEPREFIX="$PWD/build/windows/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES=ucrtbase=n,b
# A user profile whose path has spaces and non-ASCII characters, as many Windows users' have: Blender's user folder
# (add-on, extensions, core copies) and the temporary folder (the tests' .blend files and caches) live in it. It is
# on drive Z: (Unix /), beside the repository, as C:\ holds both on most Windows machines (Wine's own temporary folder
# on C: would put a test's .blend on another drive than the samples, where Blender rightly stores no relative path).
profile="$PWD/build/windows/profile Usuário é 用户"
mkdir -p "$profile/Temp"
if [ "$(cat "$WINEPREFIX/.meniscus-profile" 2>/dev/null)" != "$profile" ]; then
  [ -d "$WINEPREFIX" ] || /usr/lib/wine/wine64 wineboot --init > /dev/null 2>&1 || true
  for variable in TEMP TMP; do
    : | LC_ALL=C.UTF-8 /usr/lib/wine/wine64 reg add 'HKCU\Environment' /v "$variable" /t REG_SZ \
      /d "Z:${profile//\//\\}\\Temp" /f 2>&1 | cat > /dev/null
  done
  echo "$profile" > "$WINEPREFIX/.meniscus-profile"
fi

# What Windows functions Wine 8 lacks and numpy, Python 3.13 and bpy 5.2 need, given to each Windows CPython by the
# harness (tests/windows/wine_shims.py; nothing of it is in a package).
wine_shims() { python3 tests/windows/wine_shims.py "$1" > /dev/null; }
for python_version in 3.10 3.11 3.13; do
  tag="cp${python_version/./}"
  started=$SECONDS
  python="$(windows_python "$python_version")"
  wine_shims "$python"
  numpy_version=1.26.4 checks=()  # the numpy of bpy 4.5; it has no wheel for 3.13
  [ "$python_version" = 3.13 ] && numpy_version=2.5.5  # the numpy of bpy 5.2
  # The legacy zip's Python (Blender 3.4-4.1 on Windows): its core's build and install, checked in one frame; every
  # other check runs on 3.11 and 3.13 (the same code, built the same way).
  [ "$python_version" = 3.10 ] && checks=(--quick)
  numpy="build/windows/downloads/numpy-$numpy_version-$tag-$tag-win_amd64.whl"
  [ -f "$numpy" ] || python3 -m pip download -q --no-deps --only-binary=:all: --platform win_amd64 \
    --python-version "$python_version" --disable-pip-version-check -d build/windows/downloads \
    "numpy==$numpy_version" 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
  echo "== Windows CPython $python_version under Wine${checks:+ (install, import, one frame)}"
  python3 tests/windows/test_wheels.py --python "$python" \
    --wheel "dist/meniscus-$version-$tag-$tag-win_amd64.whl" --numpy "$numpy" --linux-cli build/bin/meniscus \
    "${checks[@]}"
  echo "($((SECONDS - started)) s)"
done

# The Mantaflow caches the suite reads are baked by Debian's Blender (nothing to do when up to date) into build/; the
# suite looks for them under MENISCUS_BUILD, which here names the mingw-w64 build.
MENISCUS_BUILD=build bash tests/mantaflow/bake.sh /usr/bin/blender > /dev/null
ln -sfn "$PWD/build/mantaflow" build-windows/mantaflow
for blender_version in 4.5 5.2; do
  python_version=3.11 not_run=""
  if [ "$blender_version" = 5.2 ]; then
    python_version=3.13
    # Blender 5.2 reads no image file under Wine 8 (docs/development.md, "What Wine cannot run"): the two scripts
    # that read their renders back run in 4.5 only, and so does the other render script (the slowest under Wine).
    not_run="test_first_light test_render_animation test_render_failure"
  fi
  echo "== Blender $blender_version (Windows bpy from PyPI, Windows CPython $python_version) under Wine with the" \
       "Windows extension zip"
  started=$SECONDS
  MENISCUS_BLENDER_NOT_RUN="$not_run" MENISCUS_BLENDER_NOT_RUN_REASON="run under Windows bpy 4.5 only: Blender 5.2 \
reads no image file under Wine 8 (VirtualAlloc2 placeholders), and renders are the slowest scripts under Wine" \
  TMPDIR="$profile" MENISCUS_WINDOWS_PYTHON="$PWD/$(windows_python "$python_version")" \
    MENISCUS_WINDOWS_PYTHONPATH="$PWD/$(windows_bpy "$blender_version")" MENISCUS_BUILD="$PWD/build-windows" \
    bash tests/blender/run.sh tests/windows/python-wine "dist/meniscus-$version-windows_x64.zip" extension
  echo "($((SECONDS - started)) s)"
done
