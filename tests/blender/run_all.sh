#!/usr/bin/env bash
# Runs every headless Blender test (tests/blender/test_*.py), each in a fresh Debian Blender; stops at the first
# failure and shows the end of its log.
#   tests/blender/run_all.sh [ADDON_DIR]      ADDON_DIR holds the staged 'meniscus' package (default build/addon)
# BLENDER overrides the Blender executable (default /usr/bin/blender).
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
addon_dir="$(realpath "${1:-$repo/build/addon}")"
blender="${BLENDER:-/usr/bin/blender}"

if [[ ! -d "$addon_dir/meniscus" ]]; then
  echo "no 'meniscus' package in $addon_dir (build first: cmake --build build)" >&2
  exit 2
fi

log_dir="$(mktemp -d -t meniscus_blender_tests.XXXXXX)"
trap 'rm -rf "$log_dir"' EXIT
count=0
for test in "$repo"/tests/blender/test_*.py; do
  name="$(basename "$test" .py)"
  log="$log_dir/$name.log"
  start=$SECONDS
  # --python-exit-code 1: an exception escaping the script (a failed check) becomes exit status 1.
  if "$blender" -b --factory-startup --python-exit-code 1 --python "$test" -- --addon-path "$addon_dir" >"$log" 2>&1; then
    echo "PASS $name ($((SECONDS - start)) s): $(grep -E '^[0-9]+ passed' "$log" | tail -1)"
    count=$((count + 1))
  else
    echo "FAIL $name ($((SECONDS - start)) s); end of its log:"
    grep -v "^Fra:" "$log" | tail -60
    exit 1
  fi
done
echo "all $count Blender test scripts passed"
