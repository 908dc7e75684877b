#!/usr/bin/env bash
# Runs the headless Blender tests against an add-on zip installed as a user installs it:
#   tests/blender/run.sh BLENDER ZIP extension|legacy
# BLENDER is a Blender executable (/usr/bin/blender) or a Python whose environment has the `bpy` module from PyPI
# (build/venv/bpy-4.5/bin/python). A fresh, empty user folder is made for the run (Blender's user resources: config,
# scripts, extensions); install.py installs ZIP into it through Blender's own installer, then every
# tests/blender/test_*.py (or the scripts MENISCUS_BLENDER_SCRIPTS names) runs in its own process, on its own copy of
# that user folder, and enables the installed add-on. The scripts run MENISCUS_BLENDER_JOBS at a time (default: one
# per core); their results are printed in the scripts' order. The first failure in that order fails the run and
# shows the end of its log.
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
blender="$1"
zip="$(realpath "$2")"
kind="$3"
[[ -f "$zip" ]] || { echo "no add-on zip at $2 (build it: bash scripts/package.sh)" >&2; exit 2; }
[[ "$kind" == extension || "$kind" == legacy ]] || { echo "kind must be extension or legacy, got '$kind'" >&2; exit 2; }

user_dir="$(mktemp -d -t meniscus_blender_user.XXXXXX)"
log_dir="$(mktemp -d -t meniscus_blender_logs.XXXXXX)"
trap 'rm -rf "$user_dir" "$user_dir".* "$log_dir"' EXIT
# Every user path of Blender in the fresh folder (BLENDER_USER_RESOURCES: 4.2+; the others: every version).
export BLENDER_USER_RESOURCES="$user_dir" BLENDER_USER_CONFIG="$user_dir/config" BLENDER_USER_SCRIPTS="$user_dir/scripts" \
       BLENDER_USER_DATAFILES="$user_dir/datafiles" MENISCUS_USER_DIR="$user_dir" MENISCUS_ADDON_KIND="$kind"

run_script() {  # run_script SCRIPT ARGS...: in a fresh process of this Blender
  local script="$1"
  shift
  if [[ "$(basename "$blender")" == python* ]]; then
    "$blender" "$script" -- "$@"
  else
    # --python-exit-code 1: an exception escaping the script (a failed check) becomes exit status 1.
    "$blender" -b --factory-startup --python-exit-code 1 --python "$script" -- "$@"
  fi
}

echo "$kind zip $(basename "$zip") in $blender"
# The scripts after install.py: every test_*.py, or those MENISCUS_BLENDER_SCRIPTS names ("test_bake uninstall": names
# of scripts in tests/blender; for a quick rerun, or a step that runs a few, as tests/windows/run.sh's legacy zip).
scripts=("$repo"/tests/blender/test_*.py)
if [[ -n "${MENISCUS_BLENDER_SCRIPTS:-}" ]]; then
  scripts=()
  for name in $MENISCUS_BLENDER_SCRIPTS; do
    [[ -f "$repo/tests/blender/$name.py" ]] || { echo "MENISCUS_BLENDER_SCRIPTS: no tests/blender/$name.py" >&2; exit 2; }
    scripts+=("$repo/tests/blender/$name.py")
  done
  echo "only the scripts MENISCUS_BLENDER_SCRIPTS names: $MENISCUS_BLENDER_SCRIPTS"
fi
# A caller may leave scripts out by name, never silently: MENISCUS_BLENDER_NOT_RUN has one line per group,
# "test_a test_b: why", and each one left out is printed with its group's reason (tests/windows/run.sh).
not_run_reason() {  # not_run_reason NAME: the reason given for leaving NAME out, or nothing
  local line
  while IFS= read -r line; do
    [[ -z "${line// /}" ]] && continue
    [[ "$line" == *:* && -n "${line#*:}" ]] || { echo "MENISCUS_BLENDER_NOT_RUN: no reason in '$line'" >&2; exit 2; }
    [[ " ${line%%:*} " == *" $1 "* ]] && { echo "${line#*: }"; return 0; }
  done <<< "${MENISCUS_BLENDER_NOT_RUN:-}"
  return 0
}
# install.py alone, into the run's user folder; it names the version (one start of Blender less: under Wine each
# costs seconds).
log="$log_dir/install.log"
start=$SECONDS
if run_script "$repo/tests/blender/install.py" "$zip" "$kind" >"$log" 2>&1; then
  echo "PASS install ($((SECONDS - start)) s): $(grep -E '^[0-9]+ passed' "$log" | tail -1)"
  version="$(sed -n 's/^BLENDER_VERSION //p' "$log")"
else
  echo "FAIL install ($((SECONDS - start)) s); end of its log:"
  grep -v "^Fra:" "$log" | tail -60
  exit 1
fi

# The scripts run side by side (each is mostly one thread; Blender's start-up is much of its time). Each has its own
# copy of the installed user folder, so that one that changes the installation (test_safe_update's update,
# uninstall's removal) or writes preferences, extensions or the core's copies there cannot affect another.
jobs="${MENISCUS_BLENDER_JOBS:-$(nproc)}"
[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "MENISCUS_BLENDER_JOBS must be a positive number, got '$jobs'" >&2; exit 2; }
names=()
for test in "${scripts[@]}"; do
  name="$(basename "$test" .py)"
  reason="$(not_run_reason "$name")"
  [[ -n "$reason" ]] && names+=("NOT RUN $name: $reason") || names+=("$name")
done
run_in_copy() {  # run_in_copy NAME: one script in its copy of the user folder; its status and seconds go to NAME.done
  local name="$1" copy="$user_dir.$1" start=$SECONDS status=0
  { cp -a "$user_dir" "$copy" &&
    BLENDER_USER_RESOURCES="$copy" BLENDER_USER_CONFIG="$copy/config" BLENDER_USER_SCRIPTS="$copy/scripts" \
      BLENDER_USER_DATAFILES="$copy/datafiles" MENISCUS_USER_DIR="$copy" \
      run_script "$repo/tests/blender/$name.py" "$zip" "$kind"; } >"$log_dir/$name.log" 2>&1 || status=$?
  rm -rf "$copy"
  echo "$status $((SECONDS - start))" > "$log_dir/$name.status"
  mv "$log_dir/$name.status" "$log_dir/$name.done"  # whole, for the loop below that waits for it
}
count=1 next=0 shown=0 started=0
while ((shown < ${#names[@]})); do
  finished=$(find "$log_dir" -name '*.done' | wc -l)
  while ((next < ${#names[@]} && started - finished < jobs)); do  # start scripts while a slot is free
    if [[ "${names[next]}" != "NOT RUN "* ]]; then
      run_in_copy "${names[next]}" &
      started=$((started + 1))
    fi
    next=$((next + 1))
  done
  name="${names[shown]}"
  if [[ "$name" == "NOT RUN "* ]]; then
    echo "$name"
  elif [[ -f "$log_dir/$name.done" ]]; then
    read -r status seconds < "$log_dir/$name.done"
    log="$log_dir/$name.log"
    if ((status != 0)); then
      echo "FAIL $name ($seconds s); end of its log:"
      grep -v "^Fra:" "$log" | tail -60
      wait  # the scripts already started end on their own (no new one starts)
      exit 1
    fi
    echo "PASS $name ($seconds s): $(grep -E '^[0-9]+ passed' "$log" | tail -1)"
    count=$((count + 1))
  else
    sleep 0.2  # polled: `wait -n` misses a script that ended before it was called
    continue
  fi
  shown=$((shown + 1))
done
echo "all $count Blender test scripts passed on Blender $version ($kind)"
