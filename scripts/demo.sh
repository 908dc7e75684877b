#!/usr/bin/env bash
# The main job: install and build, reconstruct the bundled double dam break sequence with the command-line tool,
# then render one frame of it in Blender's Cycles, headless. Prints the PNG's path last.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh

out=build/demo
mkdir -p "$out/meshes"
echo "== Reconstructing blend_samples/double_dam_break (frames 20-39)"
build/bin/meniscus reconstruct 'blend_samples/double_dam_break/double_dam_break_{}.vtk' -o "$out/meshes/surface_{}.ply" \
  -r 0.025 -l 2 -c 0.5 -a velocity --stats "$out/stats.json" --check-mesh

echo "== Rendering frame 30 with Cycles"
/usr/bin/blender -b --factory-startup --python-exit-code 1 --python blend_samples/build_demo_scene.py -- \
  --addon-path build/addon --frame 30 --output "$out/frame_0030.png" > "$out/blender.log" 2>&1 \
  || { tail -40 "$out/blender.log"; exit 1; }
echo "rendered: $(realpath "$out/frame_0030.png")"
