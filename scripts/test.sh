#!/usr/bin/env bash
# Runs every test: Catch2 (C++ core), pytest (Python API, CLI), headless Blender. Installs and builds first.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "== C++ tests (ctest)"
/usr/bin/ctest --test-dir build --output-on-failure -j2

echo "== Python tests (pytest)"
/usr/bin/python3 -m pytest -q tests/python

echo "== Blender tests (headless, Debian's Blender)"
bash tests/blender/run_all.sh build/addon

echo "== Blender tests (bpy 4.5 LTS from PyPI)"
# A venv on top of Debian's Python (numpy, pytest) with the bpy wheel; created and filled once.
[ -x build/venv-bpy/bin/python ] || /usr/bin/python3 -m venv --system-site-packages build/venv-bpy
build/venv-bpy/bin/python -c "import bpy" 2>/dev/null || build/venv-bpy/bin/pip install -q 'bpy==4.5.*'
bash tests/blender/run_bpy.sh build/addon
echo "== C++ tests under AddressSanitizer + UBSan"
bash scripts/test_sanitizers.sh
echo "== Benchmark against pysplashsurf, small version (both tools run, meshes valid; timings not judged in CI)"
bash bench/compare.sh --quick
echo "all tests passed"
