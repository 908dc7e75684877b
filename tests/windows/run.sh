#!/usr/bin/env bash
# The Windows packages of dist/ (scripts/package_windows.sh) tested under Wine, as scripts/test.sh's Windows section
# runs them: each win_amd64 wheel installed with pip into its Windows CPython from PyPI (scripts/lib.sh:
# windows_python), then tests/windows/test_wheels.py (the Python API, the console script, readers, exit codes,
# non-ASCII names, a long path, against the Linux build). Needs the Linux build (build/bin/meniscus) and dist/.
#   bash tests/windows/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
export WINEPREFIX="$PWD/build/windows/wineprefix" WINEDEBUG=-all
[ -d "$WINEPREFIX" ] || /usr/lib/wine/wine64 wineboot --init > /dev/null 2>&1 || true

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
