#!/usr/bin/env bash
# The Windows packages of dist/ (scripts/package_windows.sh) tested under Wine, as scripts/test.sh's Windows section
# runs them: each win_amd64 wheel installed with pip into its Windows CPython from PyPI (scripts/lib.sh:
# windows_python), then tests/windows/test_wheels.py (the Python API, the console script, readers, exit codes,
# non-ASCII names, a long path, against the Linux build); then the headless Blender suite (tests/blender/run.sh) with
# the extension zip installed into the Windows `bpy` 4.5 from PyPI in Windows CPython 3.11 (tests/windows/python-wine).
# Needs the Linux build (build/bin/meniscus), the mingw-w64 build (build-windows/, scripts/build_windows.sh: the
# command line the farm and bake tests run) and dist/.
#   bash tests/windows/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
export WINEPREFIX="$PWD/build/windows/wineprefix" WINEDEBUG=-all
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

numpy_version=1.26.4  # the last numpy whose win_amd64 wheels import under Debian 12's Wine 8 (2.x needs ucrtbase
                      # functions Wine lacks); it has no wheel for 3.13
for python_version in 3.10 3.11; do
  tag="cp${python_version/./}"
  started=$SECONDS
  python="$(windows_python "$python_version")"
  numpy="build/windows/downloads/numpy-$numpy_version-$tag-$tag-win_amd64.whl"
  [ -f "$numpy" ] || python3 -m pip download -q --no-deps --only-binary=:all: --platform win_amd64 \
    --python-version "$python_version" --disable-pip-version-check -d build/windows/downloads \
    "numpy==$numpy_version" 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
  echo "== Windows CPython $python_version under Wine"
  python3 tests/windows/test_wheels.py --python "$python" --wheel "dist/meniscus-$version-$tag-$tag-win_amd64.whl" \
    --numpy "$numpy" --linux-cli build/bin/meniscus
  echo "($((SECONDS - started)) s)"
done

echo "== Blender 4.5 (Windows bpy from PyPI, Windows CPython 3.11) under Wine with the Windows extension zip"
started=$SECONDS
# The Mantaflow caches the suite reads are baked by Debian's Blender (nothing to do when up to date) into build/; the
# suite looks for them under MENISCUS_BUILD, which here names the mingw-w64 build.
MENISCUS_BUILD=build bash tests/mantaflow/bake.sh /usr/bin/blender > /dev/null
ln -sfn "$PWD/build/mantaflow" build-windows/mantaflow
TMPDIR="$profile" MENISCUS_WINDOWS_PYTHON="$PWD/$(windows_python 3.11)" MENISCUS_WINDOWS_PYTHONPATH="$PWD/$(windows_bpy 4.5)" \
  MENISCUS_BUILD="$PWD/build-windows" bash tests/blender/run.sh tests/windows/python-wine \
  "dist/meniscus-$version-windows_x64.zip" extension
echo "($((SECONDS - started)) s)"
