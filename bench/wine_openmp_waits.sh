#!/usr/bin/env bash
# OpenMP regions and barriers, Linux build against the Windows build under Wine (bench/wine_openmp_waits.cpp):
#   bash bench/wine_openmp_waits.sh [COUNT]
# Builds both into build/wine_openmp_waits/ (needs mingw-w64 and Wine: scripts/build_windows.sh installs them) and
# prints microseconds per region or barrier, the two builds run alternately, each median of 5, with the load average.
set -euo pipefail
cd "$(dirname "$0")/.."
count="${1:-1000}"
out=build/wine_openmp_waits
mkdir -p "$out"
g++ -O2 -fopenmp bench/wine_openmp_waits.cpp -o "$out/waits"
x86_64-w64-mingw32-g++-posix -O2 -fopenmp -static bench/wine_openmp_waits.cpp -o "$out/waits.exe"
export WINEPREFIX="$PWD/build-windows/wineprefix" WINEDEBUG=-all
median() { sort -g | sed -n 3p; }
echo "OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-(unset)}, load average $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores"
echo "| what | threads | Linux (us) | Windows under Wine (us) |"
echo "|---|---:|---:|---:|"
for what in regions barriers; do
  for threads in 1 2; do
    linux=() windows=()
    for _ in 1 2 3 4 5; do
      linux+=("$("$out/waits" "$what" "$threads" "$count")")
      windows+=("$(/usr/lib/wine/wine64 "$out/waits.exe" "$what" "$threads" "$count" | tr -d '\r' | cat)")
    done
    echo "| $what | $threads | $(printf '%s\n' "${linux[@]}" | median) | $(printf '%s\n' "${windows[@]}" | median) |"
  done
done
