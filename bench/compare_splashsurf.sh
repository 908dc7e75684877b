#!/usr/bin/env bash
# Builds Meniscus, sets up a venv with the reference implementation (pysplashsurf from PyPI) and compares them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source bench/reference_venv.sh
build/venv-bench/bin/python bench/compare_splashsurf.py "$@"
