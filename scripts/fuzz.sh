#!/usr/bin/env bash
# Builds the libFuzzer harnesses in fuzz/ with clang (AddressSanitizer + UBSan, every UB report fatal) and runs each
# for a fixed time against its committed seed corpus fuzz/corpus/<reader>/, then reports executions, coverage and
# findings per harness. Exits 1 when any harness found something (the inputs are in build-fuzz/artifacts/).
#
#   scripts/fuzz.sh [SECONDS_PER_HARNESS (default 60)] [HARNESS ...]
#   e.g. scripts/fuzz.sh 120 vtu npz     # only fuzz_read_vtu and fuzz_read_npz, 2 minutes each
#
# Harnesses: vtk bgeo vtu ply npy npz csv xyz houdini vdb (one reader each), particles (read_particles: gzip, detection, all
# readers), mesh (read_mesh: PLY and OBJ), mantaflow (the Mantaflow cache parsers), blosc (the Blosc decoder). New
# inputs go to build-fuzz/work/<harness>/, never into the seed corpus.
# Runs one harness at a time on one core (FUZZ_JOBS=2 runs two at once). Needs clang and its runtime:
# apt-get install clang libclang-rt-14-dev (done here when missing and we are root).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
shift || true
all=(vtk bgeo vtu ply npy npz csv xyz houdini particles mesh mantaflow vdb blosc)
harnesses=("$@")
[ ${#harnesses[@]} -eq 0 ] && harnesses=("${all[@]}")
jobs=${FUZZ_JOBS:-1}

CXX=${CXX:-clang++}
if ! command -v "$CXX" > /dev/null || ! echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }' |
    "$CXX" -x c++ -fsanitize=fuzzer - -o /tmp/meniscus_fuzz_probe 2> /dev/null; then
  if [ "$(id -u)" -eq 0 ] && command -v apt-get > /dev/null; then
    echo "fuzz: installing clang and libclang-rt-14-dev"
    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq clang libclang-rt-14-dev > /dev/null
  else
    echo "fuzz: needs clang with libFuzzer (Debian: apt-get install clang libclang-rt-14-dev)" >&2
    exit 2
  fi
fi
rm -f /tmp/meniscus_fuzz_probe

out=build-fuzz
mkdir -p "$out/obj" "$out/work" "$out/artifacts" "$out/logs"
flags=(-std=c++17 -g -O1 -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=all
       -Inative/core -DMENISCUS_VERSION=\"fuzz\")

# The readers, built once with coverage instrumentation (rebuilt when a source or header is newer).
objects=()
for src in $(find native/core/io -name '*.cpp' | sort) native/core/base/platform.cpp native/core/base/decimal.cpp native/core/mesh/mesh.cpp; do
  obj="$out/obj/$(echo "${src#native/core/}" | tr / _ | sed 's/\.cpp$//').o"
  if [ ! -f "$obj" ] || [ "$src" -nt "$obj" ] || [ -n "$(find native/core/io native/core/base -name '*.h' -newer "$obj")" ]; then
    echo "fuzz: compiling $src"
    "$CXX" "${flags[@]}" -fsanitize=fuzzer-no-link -c "$src" -o "$obj"
  fi
  objects+=("$obj")
done
for h in "${harnesses[@]}"; do
  bin="$out/fuzz_read_$h"
  src="fuzz/fuzz_read_$h.cpp"
  [ -f "$src" ] || { echo "fuzz: no harness $src" >&2; exit 2; }
  if [ ! -f "$bin" ] || [ "$src" -nt "$bin" ] || [ fuzz/fuzz_common.h -nt "$bin" ] || [ -n "$(find "$out/obj" -newer "$bin")" ]; then
    echo "fuzz: linking $bin"
    "$CXX" "${flags[@]}" -fsanitize=fuzzer "$src" "${objects[@]}" -lz -o "$bin"
  fi
done

# Allocation limit per harness: a reader may allocate a small multiple of its input (64 KiB at most here); the
# zlib-based paths (and Houdini constant pages) may expand up to max_inflated_size (64x + 64 MiB), so they get more room.
malloc_limit() {
  case "$1" in
    vtu|npz|houdini|particles|mesh|vdb) echo 160 ;;
    *) echo 16 ;;
  esac
}

run_one() {
  local h=$1
  mkdir -p "$out/work/$h"
  # -timeout: one input taking 10 s is a hang; -rss_limit_mb bounds the whole process.
  "$out/fuzz_read_$h" "$out/work/$h" "fuzz/corpus/$h" -max_total_time="$seconds" -max_len=65536 -timeout=10 \
      -rss_limit_mb=2048 -malloc_limit_mb="$(malloc_limit "$h")" -artifact_prefix="$out/artifacts/$h-" \
      -print_final_stats=1 > "$out/logs/$h.log" 2>&1 || true
}

echo "fuzz: ${#harnesses[@]} harnesses, ${seconds} s each, $jobs at a time"
running=0
for h in "${harnesses[@]}"; do
  find "$out/artifacts" -name "$h-*" -type f -delete
  run_one "$h" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

status=0
printf '%-10s %10s %8s %8s %6s  %s\n' harness execs exec/s cov corpus findings
for h in "${harnesses[@]}"; do
  log="$out/logs/$h.log"
  stat() { { grep -o "$1 *[0-9]*" "$log" || true; } | tail -1 | grep -o '[0-9]*$' || echo "?"; }
  execs=$(stat 'stat::number_of_executed_units:')
  rate=$(stat 'stat::average_exec_per_sec:')
  cov=$(stat 'cov:')
  corpus=$(find "$out/work/$h" -type f | wc -l)
  findings=$(find "$out/artifacts" -name "$h-*" -type f | wc -l)
  note=$findings
  if [ "$findings" -gt 0 ]; then
    status=1
    note="$findings: $(find "$out/artifacts" -name "$h-*" -type f | head -3 | tr '\n' ' ')"
  fi
  printf '%-10s %10s %8s %8s %6s  %s\n' "$h" "$execs" "$rate" "$cov" "$corpus" "$note"
done
[ "$status" -eq 0 ] && echo "fuzz: no findings" || echo "fuzz: FINDINGS — see $out/logs/<harness>.log and the artifacts" >&2
exit "$status"
