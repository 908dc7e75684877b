#!/usr/bin/env bash
# Runs the headless Blender tests (tests/blender/test_*.py) as plain Python with the `bpy` module from PyPI
# (Blender 4.5 LTS for Python 3.11), each in a fresh process; stops at the first failure and shows its log.
#   tests/blender/run_bpy.sh [ADDON_DIR]      ADDON_DIR holds the staged 'meniscus' package (default build/addon)
# BPY_PYTHON overrides the interpreter (default build/venv-bpy/bin/python). Make the venv with:
#   /usr/bin/python3 -m venv --system-site-packages build/venv-bpy && build/venv-bpy/bin/pip install 'bpy==4.5.*'
# The verdict is each script's exit status; the scripts end with os._exit after printing their summary, so a
# crash while a bpy wheel tears down at interpreter exit cannot turn a pass into a failure.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
addon_dir="$(realpath "${1:-$repo/build/addon}")"
python="${BPY_PYTHON:-$repo/build/venv-bpy/bin/python}"

if [[ ! -x "$python" ]] || ! "$python" -c "import bpy" >/dev/null 2>&1; then
  echo "no bpy in $python (see the header of $0 to make the venv)" >&2
  exit 2
fi
if [[ ! -d "$addon_dir/meniscus" ]]; then
  echo "no 'meniscus' package in $addon_dir (build first: cmake --build build)" >&2
  exit 2
fi
version="$("$python" -c "import bpy; print(bpy.app.version_string)" 2>/dev/null | tail -1)"
echo "bpy $version ($python)"

log_dir="$(mktemp -d -t meniscus_bpy_tests.XXXXXX)"
trap 'rm -rf "$log_dir"' EXIT
count=0
for test in "$repo"/tests/blender/test_*.py; do
  name="$(basename "$test" .py)"
  log="$log_dir/$name.log"
  start=$SECONDS
  if "$python" "$test" -- --addon-path "$addon_dir" >"$log" 2>&1; then
    echo "PASS $name ($((SECONDS - start)) s): $(grep -E '^[0-9]+ passed' "$log" | tail -1)"
    count=$((count + 1))
  else
    echo "FAIL $name ($((SECONDS - start)) s); end of its log:"
    grep -v "^Fra:" "$log" | tail -60
    exit 1
  fi
done
echo "all $count Blender test scripts passed under bpy $version"
