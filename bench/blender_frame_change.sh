#!/usr/bin/env bash
# Frame change -> updated ~1 M-triangle mesh in Blender, with the core's and Blender's shares, on every tested Blender:
# Debian's 3.4 (legacy zip) and bpy 4.2, 4.5, 5.0, 5.2 (extension zip), each with the add-on installed from dist/
# into a fresh user folder as a user installs it. Writes bench/results/blender_frame_change.md and .json.
#   bash bench/blender_frame_change.sh [VERSION ...]     e.g. 3.4 5.2 (default: all)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/package.sh > build/package.log 2>&1 || { tail -30 build/package.log; exit 1; }
source scripts/lib.sh
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"

mkdir -p build/bench
outputs=()
for blender_version in ${@:-3.4 4.2 4.5 5.0 5.2}; do
  if [ "$blender_version" = 3.4 ]; then
    program=/usr/bin/blender kind=legacy zip="dist/meniscus-$version-legacy-linux_x64.zip"
  else
    program="$(bpy_venv "$blender_version")" kind=extension zip="dist/meniscus-$version-linux_x64.zip"
  fi
  user_dir="$(mktemp -d -t meniscus_bench_user.XXXXXX)"
  export BLENDER_USER_RESOURCES="$user_dir" BLENDER_USER_CONFIG="$user_dir/config" BLENDER_USER_SCRIPTS="$user_dir/scripts" \
         MENISCUS_USER_DIR="$user_dir" MENISCUS_ADDON_KIND="$kind"
  run() {
    if [ "$kind" = legacy ]; then "$program" -b --factory-startup --python-exit-code 1 --python "$@"; else "$program" "$@"; fi
  }
  run tests/blender/install.py -- "$zip" "$kind" > build/bench/install_"$blender_version".log 2>&1 \
    || { tail -20 build/bench/install_"$blender_version".log; exit 1; }
  run bench/blender_frame_change.py -- --json "build/bench/blender_frame_change_$blender_version.json"
  outputs+=("build/bench/blender_frame_change_$blender_version.json")
  rm -rf "$user_dir"
done
/usr/bin/python3 bench/blender_frame_change.py --report "${outputs[@]}"
