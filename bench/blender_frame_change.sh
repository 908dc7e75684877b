#!/usr/bin/env bash
# Frame change -> updated ~1 M-triangle mesh in Blender, with the core's and Blender's shares, on Debian's
# Blender 3.4 and on bpy 4.5 LTS (PyPI). Writes bench/results/blender_frame_change.md and .json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

# The bpy 4.5 venv, created and filled once exactly as scripts/test.sh does.
[ -x build/venv-bpy/bin/python ] || /usr/bin/python3 -m venv --system-site-packages build/venv-bpy
build/venv-bpy/bin/python -c "import bpy" 2>/dev/null || build/venv-bpy/bin/pip install -q 'bpy==4.5.*'

mkdir -p build/bench
blender -b --factory-startup --python-exit-code 1 --python bench/blender_frame_change.py -- \
    --addon-path build/addon --json build/bench/blender_frame_change_3.4.json
build/venv-bpy/bin/python bench/blender_frame_change.py -- \
    --addon-path build/addon --json build/bench/blender_frame_change_4.5.json
/usr/bin/python3 bench/blender_frame_change.py --report \
    build/bench/blender_frame_change_3.4.json build/bench/blender_frame_change_4.5.json
