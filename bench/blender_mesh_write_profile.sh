#!/usr/bin/env bash
# Per-step profile of the ~1 M-triangle mesh write and the evaluation after it, on Debian's Blender and on bpy
# 4.2, 4.5, 5.0 and 5.2 (the venvs scripts/test.sh uses; only bpy and numpy are needed in Blender):
#   bash bench/blender_mesh_write_profile.sh
# Writes bench/results/blender_mesh_write_profile.md and .json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
source scripts/lib.sh
/usr/bin/python3 bench/blender_mesh_write_profile.py --prepare --addon-path build/addon

mkdir -p build/bench
outputs=()
blender -b --factory-startup --python-exit-code 1 --python bench/blender_mesh_write_profile.py -- \
    --addon-path build/addon --json build/bench/mesh_write_profile_blender.json
outputs+=(build/bench/mesh_write_profile_blender.json)
for version in 4.2 4.5 5.0 5.2; do
  python="$(bpy_venv "$version")"
  name="_$version"
  "$python" bench/blender_mesh_write_profile.py -- --addon-path build/addon \
      --json "build/bench/mesh_write_profile${name}.json"
  outputs+=("build/bench/mesh_write_profile${name}.json")
done
/usr/bin/python3 bench/blender_mesh_write_profile.py --report "${outputs[@]}"
