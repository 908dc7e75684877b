#!/usr/bin/env bash
# Frame change -> updated ~1 M-triangle mesh in Blender, with the core's and Blender's shares, on Debian's
# Blender 3.4 and on bpy 4.5 LTS (PyPI), plus any further bpy interpreter listed in BPY_PYTHONS (space-separated;
# Python 3.11 only, like the core), e.g.
#   BPY_PYTHONS="/tmp/venvs/bpy-4.2/bin/python /tmp/venvs/bpy-5.0/bin/python" bash bench/blender_frame_change.sh
# Writes bench/results/blender_frame_change.md and .json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

source scripts/lib.sh
bpy45="$(bpy_venv 4.5)"  # the venv scripts/test.sh uses

mkdir -p build/bench
blender -b --factory-startup --python-exit-code 1 --python bench/blender_frame_change.py -- \
    --addon-path build/addon --json build/bench/blender_frame_change_3.4.json
"$bpy45" bench/blender_frame_change.py -- \
    --addon-path build/addon --json build/bench/blender_frame_change_4.5.json
outputs=(build/bench/blender_frame_change_3.4.json build/bench/blender_frame_change_4.5.json)
for python in ${BPY_PYTHONS:-}; do
  version="$("$python" -c "import bpy; print('%d.%d' % bpy.app.version[:2])" 2>/dev/null | tail -1)"
  "$python" bench/blender_frame_change.py -- --addon-path build/addon \
      --json "build/bench/blender_frame_change_${version}.json"
  outputs+=("build/bench/blender_frame_change_${version}.json")
done
/usr/bin/python3 bench/blender_frame_change.py --report "${outputs[@]}"
