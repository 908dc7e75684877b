#!/usr/bin/env bash
# Builds Meniscus, sets up a venv with the reference implementation (pysplashsurf from PyPI) and compares them.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
dpkg-query -W -f='${Status}' python3-venv 2>/dev/null | grep -q "install ok installed" || \
  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv > /dev/null; }
[ -x build/venv-bench/bin/python ] || /usr/bin/python3 -m venv --system-site-packages build/venv-bench
build/venv-bench/bin/python -c "import pysplashsurf" 2>/dev/null || build/venv-bench/bin/pip install -q pysplashsurf==0.14.1.0
build/venv-bench/bin/python bench/compare_splashsurf.py "$@"
