#!/usr/bin/env bash
# Installs what Meniscus needs on Debian 12 (idempotent: does nothing when all is there) and builds it into build/.
# Used by the two README commands; safe to run again at any time.
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/lib.sh
require_packages "${MENISCUS_BUILD_PACKAGES[@]}" blender xvfb

# Debian's cmake and Python: a pyenv or pip cmake/python earlier on PATH must not take over (Blender embeds the
# system Python 3.11, so the module is built for it).
/usr/bin/cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 > build-configure.log 2>&1 \
  || { cat build-configure.log; exit 1; }
/usr/bin/cmake --build build -j"$(nproc)"
