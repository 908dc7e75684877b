#!/usr/bin/env bash
# Per-step profile of the ~1 M-triangle mesh write and the evaluation after it, on Debian's Blender, on bpy 4.5 LTS
# (build/venv-bpy) and on every further bpy interpreter listed in BPY_PYTHONS (space-separated; any Python version:
# only bpy and numpy are needed in Blender), e.g.
#   BPY_PYTHONS="/tmp/venvs/bpy-4.2/bin/python /tmp/venvs/bpy-5.0/bin/python /tmp/venvs/bpy-5.2/bin/python" \
#       bash bench/blender_mesh_write_profile.sh
# Writes bench/results/blender_mesh_write_profile.md and .json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
/usr/bin/python3 bench/blender_mesh_write_profile.py --prepare --addon-path build/addon

mkdir -p build/bench
outputs=()
blender -b --factory-startup --python-exit-code 1 --python bench/blender_mesh_write_profile.py -- \
    --addon-path build/addon --json build/bench/mesh_write_profile_blender.json
outputs+=(build/bench/mesh_write_profile_blender.json)
for python in build/venv-bpy/bin/python ${BPY_PYTHONS:-}; do
  [ -x "$python" ] || { echo "skipping $python (not found)"; continue; }
  name="$(echo "$python" | tr '/' '_')"
  "$python" bench/blender_mesh_write_profile.py -- --addon-path build/addon \
      --json "build/bench/mesh_write_profile${name}.json"
  outputs+=("build/bench/mesh_write_profile${name}.json")
done
/usr/bin/python3 bench/blender_mesh_write_profile.py --report "${outputs[@]}"
