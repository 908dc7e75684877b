#!/usr/bin/env bash
# Per-stage timings and peak memory: shared frames + a generated 1 M-particle dam-break-like frame.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
[ -f build/bench/generated_1M.vtk ] || /usr/bin/python3 bench/generate_frame.py --particles 1000000 --output build/bench/generated_1M.vtk
/usr/bin/python3 bench/stages.py "$@"
