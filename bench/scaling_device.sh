#!/usr/bin/env bash
# bench/scaling.py on a lent many-core machine, inside ~6 minutes: a prebuilt build/bin/meniscus (carried over, with
# the shared libraries it needs in build/device-libs when that machine lacks them), generated 1 M and 4 M frames,
# 1, 2, 4, 8, 16 threads. Writes scaling_<cores>cores*.json and scaling_device.log into $OUT (or build/device-out).
#
#   bash bench/scaling_device.sh --prepare   # here, before: copies the CLI's non-libc libraries to build/device-libs
#   bash bench/scaling_device.sh             # there: the measurements
#
# Carry build/bin/meniscus and build/device-libs (and optionally build/bin/meniscus_before, an older build to compare
# on the same machine, and build/wheels with numpy and pysplashsurf wheels for that machine's Python).
#
# numpy makes the frames faster (plain Python otherwise, ~1 min for 4 M); pysplashsurf and numpy, when importable
# or found as wheels in build/wheels, add the reference at 1 M. Steps run in order of value, each bounded by what
# is left of the budget (SCALING_BUDGET_S, default 380 s), so a slow machine loses the last steps, not the JSON.
set -uo pipefail
cd "$(dirname "$0")/.."

if [ "${1:-}" = "--prepare" ]; then
    mkdir -p build/device-libs
    for lib in libgomp.so.1 libstdc++.so.6 libgcc_s.so.1 libz.so.1; do
        path=$(ldd build/bin/meniscus | awk -v l="$lib" '$1 == l { print $3 }')
        [ -n "$path" ] && cp -L "$path" build/device-libs/
    done
    ls -l build/device-libs
    exit 0
fi

OUT=${OUT:-build/device-out}
mkdir -p "$OUT"
LOG="$OUT/scaling_device.log"
BUDGET=${SCALING_BUDGET_S:-380}
START=$(date +%s)
exec > >(tee -a "$LOG") 2>&1

# Only the libraries this machine lacks come from the carried copies (the system's libc stays).
if ldd build/bin/meniscus | grep -q "not found"; then
    export LD_LIBRARY_PATH="$PWD/build/device-libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
fi
ldd build/bin/meniscus
build/bin/meniscus --help > /dev/null || { echo "the carried CLI does not start here"; exit 1; }
echo "cores: $(nproc); $(grep -m1 'model name' /proc/cpuinfo); load: $(cat /proc/loadavg)"
free -g | head -2

PYTHON=python3
if ! $PYTHON -c "import numpy" 2>/dev/null && ls build/wheels/*.whl > /dev/null 2>&1; then
    $PYTHON -m venv --system-site-packages build/device-venv 2>/dev/null && PYTHON=build/device-venv/bin/python \
        && $PYTHON -m pip install -q --no-index --find-links build/wheels numpy pysplashsurf \
        || { echo "wheels not installed: frames in plain Python, no reference"; PYTHON=python3; }
fi
$PYTHON -c "import numpy, pysplashsurf; print('pysplashsurf', pysplashsurf.__file__)" 2>/dev/null || echo "no pysplashsurf: ours only"
CORES=$(nproc)
THREADS=${SCALING_THREADS:-1 2 4 8 16}
[ -z "${SCALING_THREADS:-}" ] && [ "$CORES" -gt 16 ] && THREADS="$THREADS $CORES"
FRAMES=build/bench
export REFERENCE_PYTHON=$PYTHON

left() { echo $(( BUDGET - ($(date +%s) - START) )); }
step() {  # step NAME CAP_S ARGS...: one scaling.py run, killed at CAP_S seconds or when the budget is spent
    local name=$1 cap=$2; shift 2
    local seconds; seconds=$(left)
    [ "$cap" -lt "$seconds" ] && seconds=$cap
    if [ "$seconds" -lt 20 ]; then echo "== $name: skipped, budget spent"; return; fi
    echo "== $name ($seconds s at most)"
    timeout --signal=INT --kill-after=5 "$seconds" $PYTHON bench/scaling.py --frames-dir "$FRAMES" \
        --output "$OUT/scaling_${CORES}cores_$name.json" "$@"
    echo "== $name: exit $? after $(( $(date +%s) - START )) s"
}

# Frames first (their time is not measured), then the steps by value: the full pipeline at 1 M and 4 M; a 2-core
# busy machine (cores 0 and 1 only, a 50 k frame at c = 1.0: idle, beside a second CLI in a loop, beside two busy
# loops; the built-in wait policy against a shorter spin, passive waiting and libgomp's default spin, the slowest,
# last); reconstruction
# alone with the reference beside it.
$PYTHON -c "import sys; sys.path.insert(0, 'bench'); import pathlib, scaling; [scaling.generated_frame(s, pathlib.Path('$FRAMES')) for s in ('50k', '1M', '4M')]"
# SCALING_STEPS picks and orders the steps (default: all, in order of value).
STEPS=${SCALING_STEPS:-"full_1M full_1M_before busy_2cores reconstruction_1M full_4M reconstruction_4M full_1M_reference"}
for name in $STEPS; do
    case $name in
        full_1M) step full_1M 600 --sizes 1M --modes full --repeat 1 --no-reference --threads $THREADS ;;
        full_4M) step full_4M 600 --sizes 4M --modes full --repeat 1 --no-reference --threads $THREADS ;;
        busy_2cores) step busy_2cores 100 --busy --sizes 50k -c 1.0 --cpus 0,1 --threads 2 --repeat 3 --busy-env "" \
            --busy-env GOMP_SPINCOUNT=1000 --busy-env OMP_WAIT_POLICY=PASSIVE --busy-env GOMP_SPINCOUNT=300000 ;;
        reconstruction_1M) step reconstruction_1M 600 --sizes 1M --modes reconstruction --repeat 1 --threads $THREADS ;;
        reconstruction_4M) step reconstruction_4M 600 --sizes 4M --modes reconstruction --repeat 1 --threads $THREADS ;;
        full_1M_reference) step full_1M_reference 600 --sizes 1M --modes full --repeat 1 --threads $THREADS ;;
        reconstruction_13M) $PYTHON -c "import sys; sys.path.insert(0, 'bench'); import pathlib, scaling; scaling.generated_frame('13M', pathlib.Path('$FRAMES'))"
            step reconstruction_13M 600 --sizes 13M --modes reconstruction --repeat 1 --threads $THREADS ;;
        # The build before this round's changes, carried as build/bin/meniscus_before: a same-machine baseline.
        full_1M_before) [ -x build/bin/meniscus_before ] && step full_1M_before 120 --sizes 1M --modes full --repeat 1 \
            --no-reference --threads $THREADS --cli build/bin/meniscus_before ;;
        *) echo "unknown step $name" ;;
    esac
done
echo "done after $(( $(date +%s) - START )) s"
