#!/usr/bin/env bash
# The Windows packages of dist/ (scripts/package_windows.sh) tested under Wine, as scripts/test.sh's Windows section
# runs them: each win_amd64 wheel installed with pip into its Windows CPython from PyPI (scripts/lib.sh:
# windows_python), then tests/windows/test_wheels.py (3.11 and 3.13: the Python API, the console script, readers,
# exit codes, non-ASCII names, a long path, against the Linux build; 3.10: install, import and one frame, and the
# legacy zip's cp310 core with the add-on's handling of files held open, check_legacy_addon.py); then the headless
# Blender suite (tests/blender/run.sh) with the legacy zip installed into the Windows `bpy` 4.5 (install, one frame,
# removal) and the extension zip into the Windows `bpy` 4.5 (Windows CPython 3.11; every script) and 5.2 (3.13; the
# scripts whose subject differs there, the others named with their reason) from PyPI (tests/windows/python-wine).
# Python 3.13 runs with the harness's Wine shims (tests/windows/wine_shims.py: numpy 2.x and bpy 5.2 under Wine 8).
# Needs the Linux build (build/bin/meniscus), the mingw-w64 build (build-windows/, scripts/build_windows.sh: the
# command line the farm and bake tests run) and dist/.
#   bash tests/windows/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."
source scripts/lib.sh
require_packages "${MENISCUS_WINDOWS_PACKAGES[@]}"
version="$(sed -n 's/^project(meniscus VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
# WINEDLLOVERRIDES: the ucrtbase.dll shim that wine_shims (below) puts beside each Windows python.exe.
export WINEPREFIX="$PWD/build/windows/wineprefix" WINEDEBUG=-all WINEDLLOVERRIDES=ucrtbase=n,b
# A user profile whose path has spaces and non-ASCII characters, as many Windows users' have: Blender's user folder
# (add-on, extensions, core copies) and the temporary folder (the tests' .blend files and caches) live in it. It is
# on drive Z: (Unix /), beside the repository, as C:\ holds both on most Windows machines (Wine's own temporary folder
# on C: would put a test's .blend on another drive than the samples, where Blender rightly stores no relative path).
profile="$PWD/build/windows/profile Usuário é 用户"
mkdir -p "$profile/Temp"
if [ "$(cat "$WINEPREFIX/.meniscus-profile" 2>/dev/null)" != "$profile" ]; then
  [ -d "$WINEPREFIX" ] || /usr/lib/wine/wine64 wineboot --init > /dev/null 2>&1 || true
  for variable in TEMP TMP; do
    : | LC_ALL=C.UTF-8 /usr/lib/wine/wine64 reg add 'HKCU\Environment' /v "$variable" /t REG_SZ \
      /d "Z:${profile//\//\\}\\Temp" /f 2>&1 | cat > /dev/null
  done
  echo "$profile" > "$WINEPREFIX/.meniscus-profile"
fi

# The work runs in two lanes side by side, each in its own Wine prefix, so each with its own wineserver: Wine's
# processes wait on their server's replies one at a time, and one server left the cores about half idle whatever the
# number of processes (the bpy 5.2 suite with 2 or 4 scripts at once: 125 s; two of it at once on one server would
# take twice that, on two servers they took 140 s). A lane keeps to its Pythons: a wheel installed into a Windows
# CPython must not be there while a Blender suite runs the add-on in that Python.
#   lane 3.11: the cp311 wheel, then the legacy zip and the extension zip in bpy 4.5      (this prefix)
#   lane 3.10/3.13: the cp310 and cp313 wheels, then the extension zip in bpy 5.2      (a copy of it, made once)
second_prefix="$PWD/build/windows/wineprefix-2"
if [ "$(cat "$second_prefix/.meniscus-profile" 2>/dev/null)" != "$profile" ]; then
  /usr/lib/wine/wineserver -w 2> /dev/null || true  # the registry written above is saved when the server ends
  rm -rf "$second_prefix" "$second_prefix.partial"
  cp -a "$WINEPREFIX" "$second_prefix.partial"
  mv "$second_prefix.partial" "$second_prefix"
fi

# What Windows functions Wine 8 lacks and numpy, Python 3.13 and bpy 5.2 need, given to each Windows CPython by the
# harness (tests/windows/wine_shims.py; nothing of it is in a package).
wine_shims() { python3 tests/windows/wine_shims.py "$1" > /dev/null; }
wheel_checks() {  # wheel_checks VERSION: the Windows wheel for CPython VERSION in that Windows CPython
  local python_version="$1" tag="cp${1/./}" started=$SECONDS python numpy numpy_version=1.26.4 checks=()
  python="$(windows_python "$python_version")"
  wine_shims "$python"
  # numpy 1.26.4 is the numpy of bpy 4.5; it has no wheel for 3.13, where 2.5.5 is bpy 5.2's.
  [ "$python_version" = 3.13 ] && numpy_version=2.5.5
  # The legacy zip's Python (Blender 3.4-4.1 on Windows): its core's build and install, checked in one frame; every
  # other check runs on 3.11 and 3.13 (the same code, built the same way).
  [ "$python_version" = 3.10 ] && checks=(--quick --legacy-zip "dist/meniscus-$version-legacy-windows_x64.zip")
  numpy="build/windows/downloads/numpy-$numpy_version-$tag-$tag-win_amd64.whl"
  [ -f "$numpy" ] || python3 -m pip download -q --no-deps --only-binary=:all: --platform win_amd64 \
    --python-version "$python_version" --disable-pip-version-check -d build/windows/downloads \
    "numpy==$numpy_version" 2>&1 | { grep -v "^WARNING: Location" >&2 || true; }
  echo "== Windows CPython $python_version under Wine${checks:+ (install, import, one frame; legacy zip core, held files)}"
  python3 tests/windows/test_wheels.py --python "$python" \
    --wheel "dist/meniscus-$version-$tag-$tag-win_amd64.whl" --numpy "$numpy" --linux-cli build/bin/meniscus \
    "${checks[@]}"
  /usr/lib/wine/wineserver -w 2> /dev/null || true  # its server ends before the lane's Blender session starts one
  echo "($((SECONDS - started)) s)"
}

# The Mantaflow caches the suite reads are baked by Debian's Blender (nothing to do when up to date) into build/; the
# suite looks for them under MENISCUS_BUILD, which here names the mingw-w64 build.
MENISCUS_BUILD=build bash tests/mantaflow/bake.sh /usr/bin/blender > /dev/null
ln -sfn "$PWD/build/mantaflow" build-windows/mantaflow
# One Wine session per lane for its Blender suites, which run their scripts side by side (tests/blender/run.sh): its
# server and system services (services.exe, rpcss, ...) start here, once, with no script's output as theirs. Started
# by a script's process they keep its stderr, the pipe that tests/windows/python-wine reads to its end, open for as
# long as they live, and that script looked hung for minutes. Debian's Wine finds the server under TMPDIR: the suites'
# own. The session is the prefix's (WINEPREFIX).
wine_session() {  # wine_session start|stop
  if [ "$1" = start ]; then
    TMPDIR="$profile" /usr/lib/wine/wineserver -p < /dev/null > /dev/null 2>&1 || true  # Wine 8's exits 2 on success
    : | TMPDIR="$profile" /usr/lib/wine/wine64 cmd /c exit > /dev/null 2>&1
  else
    TMPDIR="$profile" /usr/lib/wine/wineserver -k 2> /dev/null || true
  fi
}

# blender_suite VERSION ZIP KIND: tests/blender/run.sh with ZIP installed into the Windows bpy VERSION, in its Windows
# CPython under Wine (MENISCUS_BLENDER_SCRIPTS and MENISCUS_BLENDER_NOT_RUN pass through).
blender_suite() {
  local python_version=3.11
  [ "$1" = 5.2 ] && python_version=3.13
  TMPDIR="$profile" MENISCUS_WINDOWS_PYTHON="$PWD/$(windows_python "$python_version")" \
    MENISCUS_WINDOWS_PYTHONPATH="$PWD/$(windows_bpy "$1")" MENISCUS_BUILD="$PWD/build-windows" \
    bash tests/blender/run.sh tests/windows/python-wine "$2" "$3"
}
extension_suite() {  # extension_suite VERSION [NOT RUN list]: the Windows extension zip in Windows bpy VERSION
  local started=$SECONDS
  echo "== Blender $1 (Windows bpy from PyPI, Windows CPython $([ "$1" = 5.2 ] && echo 3.13 || echo 3.11)) under Wine" \
       "with the Windows extension zip"
  MENISCUS_BLENDER_NOT_RUN="${2:-}" blender_suite "$1" "dist/meniscus-$version-windows_x64.zip" extension
  echo "($((SECONDS - started)) s)"
}

# Blender 5.2 runs the scripts whose subject differs on Windows between 4.5 and 5.2: the extension installer and the
# core copy (install.py, test_safe_update: Python 3.13's file functions), the cp313 core with numpy 2.x writing a
# surface with custom normals and velocity (test_mesh_write), bake and play from cache (test_bake), the exports
# (test_native_cache, test_export_render_settings: Alembic; test_farm_export: the job through the Windows command
# line) and Mantaflow's files (test_mantaflow_files). The others are named here with their reason, printed as NOT RUN
# (docs/development.md, "What Wine cannot run"); a new script runs in both until it is named here.
windows_52_not_run="test_first_light test_render_animation: Blender 5.2 reads no image file under Wine 8 (VirtualAlloc2 \
placeholders) and these read their renders back; run under Windows bpy 4.5 and in Linux bpy 5.2
test_render_failure: time (it passes in 5.2 under Wine, 74 s at load 6: a render in a new process for each policy); run \
under Windows bpy 4.5 and in Linux bpy 5.2
test_container test_live_source test_memory_release test_parameters test_playback test_register test_relative_paths \
test_user_errors: time; the add-on's own Python logic, no file or library call that differs between Blender 4.5 and 5.2 on \
Windows; run under Windows bpy 4.5 and, for 5.2's API, in Linux bpy 5.2
test_fluid_domain test_fluid_domain_bake test_fluid_domain_fill test_fluid_domain_stale: time; the domain's logic and the \
core's fill, the same on every platform (Mantaflow's files through the cp313 core on Windows: test_mantaflow_files); run \
under Windows bpy 4.5 and in Linux bpy 5.2"
lane_310_313() {
  export WINEPREFIX="$second_prefix"
  wheel_checks 3.10
  wheel_checks 3.13
  wine_session start
  extension_suite 5.2 "$windows_52_not_run"
  wine_session stop
}
lane_310_313 > build/windows-lane-310-313.log 2>&1 &
second_lane=$!
# Ends the other lane and both prefixes' servers, with every Wine process of theirs (set -e holds in the trap too).
trap 'kill "$second_lane" 2> /dev/null || true; for prefix in "$PWD/build/windows/wineprefix" "$second_prefix"; do
  WINEPREFIX="$prefix" wine_session stop; WINEPREFIX="$prefix" /usr/lib/wine/wineserver -k 2> /dev/null || true; done' EXIT

wheel_checks 3.11
wine_session start
# The legacy zip (Blender 3.4-4.1 on Windows). PyPI has no Windows bpy older than 4.2, but 4.2+ still installs legacy
# add-ons: installed into bpy 4.5 as a 4.1 user installs it (Preferences > Add-ons > Install, then enable), its cp311
# core is the one loaded (install.py: a copy of the add-on folder's core), a frame surfaces, and the enabled add-on
# is removed (uninstall.py). Its cp310 core: the 3.10 pass (check_legacy_addon.py).
echo "== Blender 4.5 (Windows bpy from PyPI, Windows CPython 3.11) under Wine with the legacy Windows zip"
started=$SECONDS
MENISCUS_BLENDER_SCRIPTS=uninstall blender_suite 4.5 "dist/meniscus-$version-legacy-windows_x64.zip" legacy
echo "($((SECONDS - started)) s)"
extension_suite 4.5
wine_session stop

second_lane_status=0
wait "$second_lane" || second_lane_status=$?
cat build/windows-lane-310-313.log
exit "$second_lane_status"
