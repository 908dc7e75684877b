#!/usr/bin/env bash
# Installs what Meniscus needs on Debian 12 (idempotent: does nothing when all is there) and builds it into build/.
# Used by the two README commands; safe to run again at any time.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake pybind11-dev catch2 libcli11-dev nlohmann-json3-dev zlib1g-dev python3-dev python3-numpy
          python3-pytest python3-venv blender xvfb)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "meniscus: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" > /dev/null
fi

# Debian's cmake and Python: a pyenv or pip cmake/python earlier on PATH must not take over (Blender embeds the
# system Python 3.11, so the module is built for it).
/usr/bin/cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3 > build-configure.log 2>&1 \
  || { cat build-configure.log; exit 1; }
/usr/bin/cmake --build build -j"$(nproc)"
