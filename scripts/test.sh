#!/usr/bin/env bash
# Runs every test: Catch2 (C++ core), pytest (Python API, CLI), headless Blender. Installs and builds first.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

echo "== C++ tests (ctest)"
/usr/bin/ctest --test-dir build --output-on-failure -j2

echo "== Python tests (pytest)"
/usr/bin/python3 -m pytest -q tests/python

echo "== Blender tests (headless)"
bash tests/blender/run_all.sh build/addon
echo "all tests passed"
