#!/usr/bin/env bash
# Speed and peak memory against the reference implementation (pysplashsurf from PyPI): builds Meniscus, sets up a venv
# with pysplashsurf, generates the 100 k / 1 M / 4 M-particle frames if missing, then runs bench/compare.py "$@".
#   bash bench/compare.sh            # full run (~40 min on 2 cores): bench/results/compare.md (and .json)
#   bash bench/compare.sh --quick    # CI version (~1-2 min): build/bench/compare_quick.md, exit 1 on any failure
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source bench/reference_venv.sh
sizes="100k 1M 4M"
for arg in "$@"; do [ "$arg" = "--quick" ] && sizes="100k"; done  # the quick run needs only the small frame
declare -A counts=([100k]=100000 [1M]=1000000 [4M]=4000000)
for size in $sizes; do
  [ -f "build/bench/generated_$size.vtk" ] || \
    /usr/bin/python3 bench/generate_frame.py --particles "${counts[$size]}" --output "build/bench/generated_$size.vtk"
done
build/venv-bench/bin/python bench/compare.py "$@"
