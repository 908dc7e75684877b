#!/usr/bin/env bash
# Bakes the Mantaflow test scenes with Debian's Blender 3.4 into build/mantaflow/<scene>_<FORMAT>/ (resolution 32,
# 24 frames): pool, open_top, moving_obstacle and splash as UNI, pool as OpenVDB. A scene whose scene.json is newer
# than bake_scene.py and this script is kept (the bake writes scene.json last), so a second run costs nothing.
#   bash tests/mantaflow/bake.sh [BLENDER]        (default /usr/bin/blender; MENISCUS_BUILD overrides build/)
set -euo pipefail
cd "$(dirname "$0")/../.."
blender="${1:-/usr/bin/blender}"
out_root="${MENISCUS_BUILD:-build}/mantaflow"
if ! command -v "$blender" > /dev/null; then
  echo "tests/mantaflow/bake.sh: no Blender at $blender (Debian's package 'blender' bakes Mantaflow)" >&2
  exit 1
fi
mkdir -p "$out_root"
# One baker at a time (pytest's workers each ask for the caches): a second would remove the first's half-made bake.
exec 9> "$out_root/.bake.lock"
flock 9
started=$SECONDS
for job in pool:UNI open_top:UNI moving_obstacle:UNI splash:UNI pool:OPENVDB; do
  scene="${job%%:*}" format="${job##*:}"
  dir="$out_root/${scene}_${format}"
  if [[ -f "$dir/scene.json" && "$dir/scene.json" -nt tests/mantaflow/bake_scene.py && "$dir/scene.json" -nt tests/mantaflow/bake.sh ]]; then
    continue
  fi
  rm -rf "$dir"  # a half-written or outdated bake must not mix its frames with the new ones
  log="$out_root/${scene}_${format}.log"
  if ! "$blender" -b --factory-startup --python tests/mantaflow/bake_scene.py -- "$dir" --scene "$scene" \
       --format "$format" --resolution 32 --frames 24 > "$log" 2>&1 || [[ ! -f "$dir/scene.json" ]]; then
    tail -30 "$log" >&2
    echo "tests/mantaflow/bake.sh: baking $scene ($format) failed; the log is $log" >&2
    exit 1
  fi
  grep "^mantaflow: baked" "$log" || true
done
echo "tests/mantaflow/bake.sh: caches in $out_root ($((SECONDS - started)) s)"
